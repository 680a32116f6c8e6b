//! The machine's threads, asked once, and the one way the crate splits independent work over
//! them: consecutive chunks of a slice on scoped threads, each chunk's result computed exactly
//! as it would be alone (no reduction across chunks), so a result does not depend on the
//! number of threads.

/// The threads to use: `RAYON_NUM_THREADS` when it is a positive number (the variable that
/// also sizes the pool of faer's parallel factorisations, so one setting bounds both), else
/// `std::thread::available_parallelism()`; asked once per process: it reads cgroup files on
/// every call, and [`super::symmetric_matvec`] runs millions of times (the soundness campaign
/// spent half its time in the kernel on it: 258 s on 2 threads before, 58 s after).
pub(crate) fn hardware_threads() -> usize {
    static THREADS: std::sync::OnceLock<usize> = std::sync::OnceLock::new();
    *THREADS.get_or_init(|| {
        threads_from(
            std::env::var("RAYON_NUM_THREADS").ok().as_deref(),
            std::thread::available_parallelism().map_or(1, |t| t.get()),
        )
    })
}

/// `setting` (the value of `RAYON_NUM_THREADS`) when it is a positive number, else `available`.
fn threads_from(setting: Option<&str>, available: usize) -> usize {
    setting
        .and_then(|v| v.trim().parse::<usize>().ok())
        .filter(|&t| t > 0)
        .unwrap_or(available)
}

/// Edges from which a pass doing about a microsecond of work per edge (the double-double
/// `Q Y`: 2.3 us per anisotropic edge; the step-2 edge bounds: 1.4 us) splits over the threads:
/// 20 ms or more of work against about 0.1 ms to start and join them.
pub(crate) const PARALLEL_EDGES: usize = 20_000;

/// `f(first, chunk)` for consecutive chunks of `items` (`first`: the chunk's offset in
/// `items`), on one scoped thread per chunk when `parallel` and the machine has more than one
/// thread (at most one chunk per thread, none empty), else once on the whole slice; the
/// results in chunk order.
pub(crate) fn in_chunks<T: Send, R: Send>(
    items: &mut [T],
    parallel: bool,
    f: impl Fn(usize, &mut [T]) -> R + Sync,
) -> Vec<R> {
    let threads = hardware_threads().min(items.len());
    if !parallel || threads < 2 {
        return vec![f(0, items)];
    }
    let chunk = items.len().div_ceil(threads);
    std::thread::scope(|scope| {
        let handles: Vec<_> = items
            .chunks_mut(chunk)
            .enumerate()
            .map(|(t, part)| {
                let f = &f;
                scope.spawn(move || f(t * chunk, part))
            })
            .collect();
        handles
            .into_iter()
            .map(|h| match h.join() {
                Ok(r) => r,
                Err(panic) => std::panic::resume_unwind(panic),
            })
            .collect()
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_positive_setting_decides_the_threads() {
        assert_eq!(threads_from(Some("1"), 8), 1);
        assert_eq!(threads_from(Some(" 3 "), 2), 3);
        for unusable in [None, Some("0"), Some(""), Some("many"), Some("-2")] {
            assert_eq!(threads_from(unusable, 2), 2, "{unusable:?}");
        }
    }

    #[test]
    fn chunks_cover_the_slice_once_in_order() {
        for len in [0usize, 1, 2, 3, 7, 100] {
            for parallel in [false, true] {
                let mut y = vec![0usize; len];
                let firsts = in_chunks(&mut y, parallel, |first, out| {
                    for (k, v) in out.iter_mut().enumerate() {
                        *v += first + k + 1;
                    }
                    first
                });
                assert_eq!(y, (1..=len).collect::<Vec<_>>());
                assert!(firsts.windows(2).all(|w| w[0] < w[1]));
                assert_eq!(firsts[0], 0);
            }
        }
    }
}
