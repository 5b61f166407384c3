//! A small measurement helper: warm-up, calibration, interleaved samples,
//! median and interquartile range.
//!
//! Every benchmark here compares subjects measured in the same run, so what
//! matters is that they see the same machine: [`interleaved`] runs one sample
//! of each subject per round, alternating the order (A B, B A, A B, …) so that
//! a slow drift (another process, frequency changes) hits them alike. Derived
//! figures (a ratio, an overhead) are computed per round from the paired
//! samples and summarized afterwards ([`paired`]), which cancels most of the
//! drift that survives the interleaving.

use std::time::{Duration, Instant};

/// How long and how often to measure.
#[derive(Debug, Clone)]
pub struct Settings {
    /// Samples per subject (the median needs ≥ 20 to be steady).
    pub samples: usize,
    /// Each sample runs enough iterations to last at least this long.
    pub min_sample: Duration,
    /// Time spent running each subject before calibrating.
    pub warmup: Duration,
}

impl Default for Settings {
    fn default() -> Self {
        Settings { samples: 31, min_sample: Duration::from_millis(2), warmup: Duration::from_millis(100) }
    }
}

impl Settings {
    /// Shorter runs for a smoke test (`--quick`).
    pub fn quick() -> Self {
        Settings { samples: 11, min_sample: Duration::from_millis(1), warmup: Duration::from_millis(20) }
    }

    /// The options every benchmark program takes (`--quick`, `--samples N`, `--json PATH`;
    /// `--bench`, which `cargo bench` passes, is ignored): the settings and where to write JSON.
    /// Anything else is an error naming it and `program`'s usage.
    pub fn from_args(
        program: &str,
        args: impl IntoIterator<Item = String>,
    ) -> Result<(Settings, Option<std::path::PathBuf>), String> {
        let mut settings = Settings::default();
        let mut json = None;
        let mut args = args.into_iter();
        while let Some(a) = args.next() {
            match a.as_str() {
                "--bench" => {}
                "--quick" => settings = Settings::quick(),
                "--samples" => match args.next().and_then(|n| n.parse().ok()) {
                    Some(n) if n > 0 => settings.samples = n,
                    _ => return Err(format!("{program}: --samples needs a whole number above 0")),
                },
                "--json" => json = Some(args.next().ok_or(format!("{program}: --json needs a PATH"))?.into()),
                other => {
                    return Err(format!("{program} [--quick] [--samples N] [--json PATH]: unknown argument `{other}`"))
                }
            }
        }
        Ok((settings, json))
    }
}

/// A set of samples (one figure per round) and its quartiles.
#[derive(Debug, Clone, PartialEq)]
pub struct Summary {
    pub median: f64,
    pub q1: f64,
    pub q3: f64,
    /// The samples in round order (unsorted), for pairing.
    pub samples: Vec<f64>,
}

impl Summary {
    pub fn of(samples: Vec<f64>) -> Summary {
        let mut sorted = samples.clone();
        sorted.sort_by(f64::total_cmp);
        Summary { median: quantile(&sorted, 0.5), q1: quantile(&sorted, 0.25), q3: quantile(&sorted, 0.75), samples }
    }

    /// The interquartile range relative to the median, in percent.
    pub fn spread_pct(&self) -> f64 {
        if self.median == 0.0 {
            0.0
        } else {
            (self.q3 - self.q1) / self.median.abs() * 100.0
        }
    }

    /// A summary of `f` applied to every sample.
    pub fn map(&self, f: impl Fn(f64) -> f64) -> Summary {
        Summary::of(self.samples.iter().map(|&x| f(x)).collect())
    }
}

/// Quantile `q` of sorted data, linearly interpolated (NaN for no data).
pub fn quantile(sorted: &[f64], q: f64) -> f64 {
    match sorted.len() {
        0 => f64::NAN,
        1 => sorted[0],
        n => {
            let pos = q.clamp(0.0, 1.0) * (n - 1) as f64;
            let lo = pos.floor() as usize;
            let hi = (lo + 1).min(n - 1);
            sorted[lo] + (sorted[hi] - sorted[lo]) * (pos - lo as f64)
        }
    }
}

/// Per-round figure `f(a, b)` from two subjects measured in the same rounds.
pub fn paired(a: &Summary, b: &Summary, f: impl Fn(f64, f64) -> f64) -> Summary {
    Summary::of(a.samples.iter().zip(&b.samples).map(|(&x, &y)| f(x, y)).collect())
}

/// The ratio `b / a` per round.
pub fn ratio(a: &Summary, b: &Summary) -> Summary {
    paired(a, b, |x, y| y / x)
}

fn time(run: &mut dyn FnMut(usize, u64), subject: usize, iters: u64) -> Duration {
    let start = Instant::now();
    run(subject, iters);
    start.elapsed()
}

/// Iterations of `subject` so that one sample lasts about `2 × min_sample`
/// (at least `min_sample` even when the first guess was a little fast).
fn calibrate(run: &mut dyn FnMut(usize, u64), subject: usize, min_sample: Duration) -> u64 {
    let mut iters = 1u64;
    loop {
        let t = time(run, subject, iters);
        if t >= min_sample / 4 || iters >= 1 << 40 {
            let per_iter = t.as_secs_f64() / iters as f64;
            let want = (2.0 * min_sample.as_secs_f64() / per_iter.max(1e-12)).ceil() as u64;
            return want.max(1);
        }
        iters *= 2;
    }
}

/// Measures `subjects.len()` subjects run by `run(subject, iters)` (which
/// runs `iters` iterations of subject `subject`), interleaved. Returns, per
/// subject, the nanoseconds per iteration of every sample.
pub fn interleaved(settings: &Settings, subjects: usize, run: &mut dyn FnMut(usize, u64)) -> Vec<Summary> {
    // Warm-up: caches, branch predictors, the allocator's free lists, the
    // CPU's clock.
    for s in 0..subjects {
        let end = Instant::now() + settings.warmup;
        while Instant::now() < end {
            run(s, 1);
        }
    }
    let iters: Vec<u64> = (0..subjects).map(|s| calibrate(run, s, settings.min_sample)).collect();
    let mut samples: Vec<Vec<f64>> = vec![Vec::with_capacity(settings.samples); subjects];
    for round in 0..settings.samples {
        for k in 0..subjects {
            let s = if round % 2 == 0 { k } else { subjects - 1 - k };
            let t = time(run, s, iters[s]);
            samples[s].push(t.as_nanos() as f64 / iters[s] as f64);
        }
    }
    samples.into_iter().map(Summary::of).collect()
}

#[cfg(test)]
mod tests {

    #[test]
    fn the_common_options_are_read_and_anything_else_is_named() {
        let args = |a: &[&str]| a.iter().map(|s| s.to_string()).collect::<Vec<_>>();
        let (s, json) = Settings::from_args("b", args(&["--bench", "--samples", "7", "--json", "x.json"])).unwrap();
        assert_eq!((s.samples, json), (7, Some("x.json".into())));
        let (s, json) = Settings::from_args("b", args(&["--quick"])).unwrap();
        assert_eq!((s.samples, json), (Settings::quick().samples, None));
        let e = Settings::from_args("b", args(&["--nope"])).unwrap_err();
        assert!(e.contains("unknown argument `--nope`"), "{e}");
        assert!(Settings::from_args("b", args(&["--samples", "x"])).is_err());
        assert!(Settings::from_args("b", args(&["--json"])).is_err());
    }
    use super::*;

    #[test]
    fn quartiles_interpolate() {
        let s = Summary::of(vec![4.0, 1.0, 3.0, 2.0, 5.0]);
        assert_eq!((s.q1, s.median, s.q3), (2.0, 3.0, 4.0));
        let s = Summary::of(vec![1.0, 2.0]);
        assert_eq!(s.median, 1.5);
        assert!(Summary::of(Vec::new()).median.is_nan());
    }

    #[test]
    fn paired_figures_follow_round_order() {
        let a = Summary::of(vec![1.0, 2.0, 4.0]);
        let b = Summary::of(vec![2.0, 2.0, 2.0]);
        assert_eq!(ratio(&a, &b).samples, vec![2.0, 1.0, 0.5]);
    }

    #[test]
    fn interleaving_alternates_the_order_and_calls_every_subject() {
        let settings = Settings { samples: 4, min_sample: Duration::from_micros(10), warmup: Duration::ZERO };
        let mut order = Vec::new();
        let out = interleaved(&settings, 2, &mut |s, iters| {
            order.push(s);
            std::hint::black_box((0..iters).sum::<u64>());
        });
        assert_eq!(out.len(), 2);
        assert!(out.iter().all(|s| s.samples.len() == 4));
        // The last 8 calls are the rounds: 0 1, 1 0, 0 1, 1 0.
        assert_eq!(order[order.len() - 8..], [0, 1, 1, 0, 0, 1, 1, 0]);
    }
}
