//! The bounds on what a robot file (and a file it includes, a skill
//! manifest) may hold and ask for: sizes, counts, lengths, rates and
//! deadlines. A file beyond them is an error at its place, never a crash or
//! a robot that cannot run. Each is re-exported by the module that checks it
//! (`config`, `include`, `manifest`, `yaml`).

/// The default cycle rate.
pub const DEFAULT_RATE_HZ: f64 = 20.0;
/// The fastest cycle rate a robot file may ask for.
pub const MAX_RATE_HZ: f64 = 100_000.0;
/// The slowest cycle rate: one cycle a day.
pub const MIN_RATE_HZ: f64 = 1.0 / 86_400.0;
/// The longest period, execution budget, liveness deadline or remote
/// timeout: a day, in ms.
pub const MAX_DEADLINE_MS: f64 = 86_400_000.0;
/// The shortest period: that of the fastest cycle, in ms.
pub const MIN_PERIOD_MS: f64 = 1000.0 / MAX_RATE_HZ;

/// What `rate_hz` accepts, in messages.
pub(crate) const RATE_RANGE: &str = "a number > 0 and ≤ 100000";
/// What `period_ms` accepts, in messages.
pub(crate) const PERIOD_RANGE: &str = "a number from 0.01 to 86400000 (10 µs to a day)";
/// What `budget_ms`, `liveness_ms` and `timeout_ms` accept, in messages.
pub(crate) const DEADLINE_RANGE: &str = "a number > 0 and ≤ 86400000 (a day)";
/// The largest parallel executor pool.
pub const MAX_THREADS: usize = 64;

/// The largest robot file (and remote skill manifest file) read: 1 MiB.
pub const MAX_ROBOT_FILE_BYTES: u64 = 1 << 20;
/// The most entries `devices:` and `skills:` may hold together.
pub const MAX_ENTRIES: usize = 1024;
/// The longest name (robot, entry, type, parameter, port, signal), in
/// characters.
pub const MAX_NAME_CHARS: usize = 256;

/// The deepest nesting of lists and mappings a robot file may use.
pub const MAX_DEPTH: usize = 64;

/// The deepest chain of includes (a file including a file including …).
pub const MAX_INCLUDE_DEPTH: usize = 16;
/// The most files one robot file may read, itself and all it includes.
pub const MAX_SOURCE_FILES: usize = 64;

/// The most inputs, outputs or parameters a manifest may declare (each).
pub const MAX_PORTS: usize = 256;
/// The longest port type (`{x: f64, y: f64}`), in characters.
pub const MAX_TYPE_CHARS: usize = 1024;
