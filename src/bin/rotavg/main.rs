//! The `rotavg` command-line tool (SPEC section 5).
fn main() {
    eprintln!("rotavg: not yet implemented");
    std::process::exit(2);
}
