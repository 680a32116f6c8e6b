//! Structure-from-motion text readers (`rotavg::io::sfm`): the first byte's bits 3-4 select
//! `read_egs` (1DSfM `EGs.txt`), `read_bundler` (Bundler v0.3) or `read_rotation_list`, its
//! low bits the reader options. Accepted view graphs go through `common::check_graph`; ground
//! truth is reordered onto graph nodes with `truth_for_nodes`.
#![no_main]

use libfuzzer_sys::fuzz_target;
use rotavg::io::sfm::{read_bundler, read_egs, read_rotation_list, truth_for_nodes};

mod common;

fuzz_target!(|data: &[u8]| {
    let Some((selector, text)) = common::split(data) else {
        return;
    };
    let options = common::options(selector);
    let truth = match (selector >> 3) & 3 {
        0 | 3 => {
            if let Ok(g) = read_egs(&text, "EGs.txt", &options) {
                common::check_graph(&g);
            }
            return;
        }
        1 => read_bundler(&text, "gt_bundle.out", &options),
        _ => read_rotation_list(&text, "gt.txt", &options),
    };
    if let Ok(truth) = truth {
        truth.iter().flatten().for_each(common::assert_rotation);
        // File ids 0..len (all present) plus some absent and huge ones.
        let ids: Vec<u64> = (0..truth.len() as u64 + 2).chain([u64::MAX]).collect();
        let mapped = truth_for_nodes(&truth, &ids);
        assert_eq!(mapped.len(), ids.len());
        assert!(mapped[truth.len()..].iter().all(Option::is_none));
    }
});
