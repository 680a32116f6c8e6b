//! g2o / TORO reader (`rotavg::io::g2o::read_g2o`) under the reader options the first byte
//! selects; accepted graphs go through `common::check_graph`.
#![no_main]

use libfuzzer_sys::fuzz_target;
use rotavg::io::g2o::read_g2o;

mod common;

fuzz_target!(|data: &[u8]| {
    let Some((selector, text)) = common::split(data) else {
        return;
    };
    if let Ok(g) = read_g2o(&text, "fuzz.g2o", &common::options(selector)) {
        common::check_graph(&g);
    }
});
