//! The `cycle:` section: the cycle's rate or period, its clock, its
//! executor, and the default deadlines of the skills' runs.

use super::check::Checker;
use super::{Node, Pos, Spanned};
use crate::limits::{DEFAULT_RATE_HZ, MAX_RATE_HZ, MAX_THREADS, MIN_RATE_HZ, RATE_RANGE};

const CYCLE_KEYS: &[&str] = &["rate_hz", "period_ms", "clock", "executor", "threads", "budget_ms", "liveness_ms"];

/// Which clock drives the cycle.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ClockKind {
    Wall,
    Simulated,
}

/// How the cycle runs the synchronous skills.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ExecutorKind {
    Serial,
    Parallel,
}

/// The `cycle:` section.
#[derive(Debug, Clone, PartialEq)]
pub struct CycleConfig {
    /// Seconds between cycles.
    pub period_s: f64,
    pub clock: ClockKind,
    pub executor: ExecutorKind,
    /// The parallel executor's pool size, if given.
    pub threads: Option<usize>,
    /// The default execution budget of a sync cskill's run, ms.
    pub budget_ms: Option<f64>,
    /// The default liveness deadline of an async cskill's or dskill's run, ms.
    pub liveness_ms: Option<f64>,
    /// Where `cycle:` is (1:1 if the file has none).
    pub pos: Pos,
}

impl CycleConfig {
    pub fn rate_hz(&self) -> f64 {
        1.0 / self.period_s
    }
}

impl Default for CycleConfig {
    fn default() -> CycleConfig {
        CycleConfig {
            period_s: 1.0 / DEFAULT_RATE_HZ,
            clock: ClockKind::Wall,
            executor: ExecutorKind::Serial,
            threads: None,
            budget_ms: None,
            liveness_ms: None,
            pos: Pos::START,
        }
    }
}

impl Checker<'_> {
    pub(super) fn cycle(&mut self, key_pos: Pos, node: Spanned<Node>) -> CycleConfig {
        let mut cycle = CycleConfig { pos: key_pos, ..CycleConfig::default() };
        let Some(entries) = self.mapping("cycle", node, "a mapping (`rate_hz:`, `clock:`, `executor:`, …)") else {
            return cycle;
        };
        let mut rate_key: Option<&str> = None;
        for (key, value) in &entries {
            let k = key.value.as_str();
            match k {
                "rate_hz" | "period_ms" => {
                    if let Some(first) = rate_key {
                        self.push(
                            key.pos,
                            format!("`cycle` takes either `rate_hz` or `period_ms`, not both (`{first}` is given too)"),
                        );
                        continue;
                    }
                    rate_key = Some(if k == "rate_hz" { "rate_hz" } else { "period_ms" });
                    if k == "rate_hz" {
                        if value.value.as_f64().is_some_and(|x| x > 0.0 && x < MIN_RATE_HZ) {
                            self.push(
                                value.pos,
                                format!(
                                    "`rate_hz` is out of range: the cycle must run at least once a day \
                                     (rate_hz ≥ 0.0000116), got {}",
                                    value.value.describe()
                                ),
                            );
                        } else if let Some(hz) = self.number(k, value, |x| x > 0.0 && x <= MAX_RATE_HZ, RATE_RANGE) {
                            cycle.period_s = 1.0 / hz;
                        }
                    } else if let Some(ms) = self.period(k, value) {
                        cycle.period_s = ms / 1000.0;
                    }
                }
                "clock" => {
                    if let Some(c) =
                        self.choice(k, value, &[("wall", ClockKind::Wall), ("simulated", ClockKind::Simulated)])
                    {
                        cycle.clock = c;
                    }
                }
                "executor" => {
                    if let Some(e) =
                        self.choice(k, value, &[("serial", ExecutorKind::Serial), ("parallel", ExecutorKind::Parallel)])
                    {
                        cycle.executor = e;
                    }
                }
                "threads" => {
                    cycle.threads = self.integer(k, value, 1, MAX_THREADS as i64).map(|n| n as usize);
                }
                "budget_ms" => cycle.budget_ms = self.deadline(k, value),
                "liveness_ms" => cycle.liveness_ms = self.deadline(k, value),
                _ => self.unknown_key(key, "in `cycle`", CYCLE_KEYS),
            }
        }
        cycle
    }
}

#[cfg(test)]
mod tests {
    use crate::config::tests::{error, skill};

    #[test]
    fn rates_and_periods_are_range_checked() {
        assert_eq!(
            error("robot: r\ncycle:\n  rate_hz: 0\n"),
            "robot.yaml:3:12: error: `rate_hz` is out of range: expects a number > 0 and ≤ 100000, got 0"
        );
        assert_eq!(
            error("robot: r\ncycle:\n  rate_hz: 200000\n"),
            "robot.yaml:3:12: error: `rate_hz` is out of range: expects a number > 0 and ≤ 100000, got 200000"
        );
        assert_eq!(
            error("robot: r\ncycle:\n  rate_hz: .nan\n"),
            "robot.yaml:3:12: error: `rate_hz` is out of range: expects a number > 0 and ≤ 100000, got .nan"
        );
        assert_eq!(
            error("robot: r\ncycle: {period_ms: -5}\n"),
            "robot.yaml:2:20: error: `period_ms` is out of range: expects a number from 0.01 to 86400000 (10 µs to a day), got -5"
        );
        assert_eq!(
            error(&skill("    period_ms: .inf\n")),
            "robot.yaml:5:16: error: `period_ms` is out of range: expects a number from 0.01 to 86400000 (10 µs to a day), got .inf"
        );
        assert_eq!(
            error(&skill("    period_ms: \"50\"\n")),
            "robot.yaml:5:16: error: `period_ms` expects a number > 0, got \"50\""
        );
    }

    #[test]
    fn rate_and_period_together_is_an_error_at_the_second() {
        assert_eq!(
            error("robot: r\ncycle:\n  period_ms: 10\n  rate_hz: 100\n"),
            "robot.yaml:4:3: error: `cycle` takes either `rate_hz` or `period_ms`, not both (`period_ms` is given too)"
        );
    }
}
