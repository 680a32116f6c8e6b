use rotavg::certify::CertifySettings;
use rotavg::certify::log::Point;
use rotavg::certify::multiple::conv_dual::{conv_dual_bound, surrogate};
use rotavg::certify::multiple::multipliers::{certificate_matrix, multipliers};
use rotavg::io::detect::{GraphFormat, ReadOptions, read_graph};
use rotavg::linalg::cholesky::ShiftedCholesky;
use rotavg::multiple::{MultipleSettings, solve_multiple};
fn main() {
    let path = std::env::args().nth(1).unwrap();
    let text = std::fs::read_to_string(&path).unwrap();
    let g = read_graph(
        &text,
        &path,
        GraphFormat::Auto,
        &ReadOptions {
            full_information: true,
            ..Default::default()
        },
    )
    .unwrap();
    let p = g.problem;
    let sol = solve_multiple(&p, &MultipleSettings::default()).unwrap();
    let y = &sol.rotations;
    let b = conv_dual_bound(&p, y, &CertifySettings::default(), Point::ConvDual, None).unwrap();
    let sur = surrogate(&p, y, &b.search.penalties).unwrap();
    let l = multipliers(&sur.problem, y).unwrap();
    let s = certificate_matrix(&sur.problem, &l).unwrap();
    let mut ch = ShiftedCholesky::new(s, 64).unwrap();
    for k in -12..4 {
        let shift = 10f64.powi(k);
        match ch.factor(shift, 0.0) {
            Some(f) => {
                println!(
                    "shift {shift:.0e}: factors, margin {:.3e}, bound {:.3e}",
                    f.margin,
                    -shift - f.margin
                );
            }
            None => println!("shift {shift:.0e}: fails"),
        }
    }
}
