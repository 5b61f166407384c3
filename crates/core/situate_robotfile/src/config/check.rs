//! The checker: a walk over the node tree that collects every error with
//! its position, and the checks of values every section shares (numbers in
//! a range, integers, one of a few words, mappings, name lengths, unknown
//! keys).

use situate_core::names::suggestion;

use super::{ConfigError, Node, Pos, SourceFile, Spanned};
use crate::limits::{DEADLINE_RANGE, MAX_DEADLINE_MS, MAX_NAME_CHARS, MIN_PERIOD_MS, PERIOD_RANGE};

/// Walks the node tree, collecting errors.
pub(super) struct Checker<'a> {
    pub(super) file: &'a str,
    /// The files read (this one and those it includes).
    pub(super) sources: Vec<SourceFile>,
    /// Errors, each with its position for sorting.
    pub(super) errors: Vec<(Pos, ConfigError)>,
    /// Entries of `devices` and `skills` read so far.
    pub(super) entries: usize,
}

pub(super) type Entries = Vec<(Spanned<String>, Spanned<Node>)>;

impl Checker<'_> {
    pub(super) fn push(&mut self, pos: Pos, message: impl Into<String>) {
        let file = self.sources.get(pos.src).map_or(self.file, |s| s.file.as_str());
        self.errors.push((pos, ConfigError::new(file, pos, message)));
    }

    pub(super) fn unknown_key(&mut self, key: &Spanned<String>, place: &str, allowed: &[&str]) {
        let hint = suggestion(&key.value, allowed.iter().copied());
        self.push(key.pos, format!("unknown key `{}` {place}{hint}", key.value));
    }

    /// A mapping's entries; null is an empty mapping. Anything else is an
    /// error "`key` expects {what}, got …".
    pub(super) fn mapping(&mut self, key: &str, node: Spanned<Node>, what: &str) -> Option<Entries> {
        match node.value {
            Node::Map(entries) => Some(entries),
            Node::Null => Some(Vec::new()),
            other => {
                self.push(node.pos, format!("`{key}` expects {what}, got {}", other.describe()));
                None
            }
        }
    }

    /// Whether `text`, a `what`, is longer than [`MAX_NAME_CHARS`] (then an
    /// error at `pos`, which does not quote it).
    pub(super) fn too_long(&mut self, what: &str, text: &str, pos: Pos) -> bool {
        let n = text.chars().count();
        if n > MAX_NAME_CHARS {
            self.push(pos, format!("{what} is {n} characters long; a name may have at most {MAX_NAME_CHARS}"));
        }
        n > MAX_NAME_CHARS
    }

    /// A number that `ok` accepts; messages say it `expects` and quote the
    /// value as written (`1e300`, not its digits), at the value.
    pub(super) fn number(
        &mut self,
        key: &str,
        value: &Spanned<Node>,
        ok: impl Fn(f64) -> bool,
        expects: &str,
    ) -> Option<f64> {
        let Some(x) = value.value.as_f64() else {
            self.push(value.pos, format!("`{key}` expects a number > 0, got {}", value.value.describe()));
            return None;
        };
        if ok(x) {
            Some(x)
        } else {
            self.push(value.pos, format!("`{key}` is out of range: expects {expects}, got {}", value.value.describe()));
            None
        }
    }

    /// A period in ms: 10 µs to a day.
    pub(super) fn period(&mut self, key: &str, value: &Spanned<Node>) -> Option<f64> {
        self.number(key, value, |x| (MIN_PERIOD_MS..=MAX_DEADLINE_MS).contains(&x), PERIOD_RANGE)
    }

    /// A deadline in ms: > 0, at most a day.
    pub(super) fn deadline(&mut self, key: &str, value: &Spanned<Node>) -> Option<f64> {
        self.number(key, value, |x| x > 0.0 && x <= MAX_DEADLINE_MS, DEADLINE_RANGE)
    }

    /// An integer in `min..=max`. An integer too large for 64 bits is out of
    /// range too, not "not an integer".
    pub(super) fn integer(&mut self, key: &str, value: &Spanned<Node>, min: i64, max: i64) -> Option<i64> {
        let n = value.value.as_i64();
        if n.is_none() && !value.value.is_integer_literal() {
            self.push(value.pos, format!("`{key}` expects an integer, got {}", value.value.describe()));
            return None;
        }
        match n.filter(|n| (min..=max).contains(n)) {
            Some(n) => Some(n),
            None => {
                self.push(
                    value.pos,
                    format!(
                        "`{key}` is out of range: expects an integer from {min} to {max}, got {}",
                        value.value.describe()
                    ),
                );
                None
            }
        }
    }

    /// One of a few words.
    pub(super) fn choice<T: Copy>(
        &mut self,
        key: &str,
        value: &Spanned<Node>,
        options: &[(&'static str, T)],
    ) -> Option<T> {
        let text = value.value.as_text();
        if let Some(&(_, v)) = options.iter().find(|(w, _)| Some(*w) == text) {
            return Some(v);
        }
        let words: Vec<String> = options.iter().map(|(w, _)| format!("`{w}`")).collect();
        let hint = text.map(|t| suggestion(t, options.iter().map(|(w, _)| *w))).unwrap_or_default();
        self.push(value.pos, format!("`{key}` expects {}, got {}{hint}", words.join(" or "), value.value.describe()));
        None
    }
}

#[cfg(test)]
mod tests {
    use crate::config::tests::{error, skill};

    #[test]
    fn numbers_out_of_range_are_quoted_as_written_at_their_place() {
        let period = "expects a number from 0.01 to 86400000 (10 µs to a day)";
        let deadline = "expects a number > 0 and ≤ 86400000 (a day)";
        // Before: accepted here, then "cycle period must be > 0 s and at most
        // a day, got 1e297 s" with no position.
        assert_eq!(
            error("robot: r\ncycle: {period_ms: 1e300}\n"),
            format!("robot.yaml:2:20: error: `period_ms` is out of range: {period}, got 1e300")
        );
        assert_eq!(
            error("robot: r\ncycle:\n  period_ms: 0.001\n"),
            format!("robot.yaml:3:14: error: `period_ms` is out of range: {period}, got 0.001")
        );
        assert_eq!(
            error("robot: r\ncycle: {rate_hz: 1e-300}\n"),
            "robot.yaml:2:18: error: `rate_hz` is out of range: the cycle must run at least once a day \
             (rate_hz ≥ 0.0000116), got 1e-300"
        );
        assert_eq!(
            error(&skill("    period_ms: 1E+300\n")),
            format!("robot.yaml:5:16: error: `period_ms` is out of range: {period}, got 1E+300")
        );
        assert_eq!(
            error(&skill("    budget_ms: 0x7fffffff\n")),
            format!("robot.yaml:5:16: error: `budget_ms` is out of range: {deadline}, got 0x7fffffff")
        );
        assert_eq!(
            error(&skill("    liveness_ms: 1e9\n")),
            format!("robot.yaml:5:18: error: `liveness_ms` is out of range: {deadline}, got 1e9")
        );
        assert_eq!(
            error("robot: r\ncycle: {budget_ms: -0.0}\n"),
            format!("robot.yaml:2:20: error: `budget_ms` is out of range: {deadline}, got -0.0")
        );
        // Before: accepted (and silently cut to a day by `situate run`).
        assert_eq!(
            error("robot: r\nskills:\n  - {name: x, remote: x.yaml, timeout_ms: 1e300}\n"),
            format!("robot.yaml:3:43: error: `timeout_ms` is out of range: {deadline}, got 1e300")
        );
        // Integers too large for 64 bits are out of range, not "not an integer".
        let int32 = "expects an integer from -2147483648 to 2147483647";
        assert_eq!(
            error(&skill("    priority: 99999999999999999999\n")),
            format!("robot.yaml:5:15: error: `priority` is out of range: {int32}, got 99999999999999999999")
        );
        assert_eq!(
            error(&skill("    priority: -0x80000001\n")),
            "robot.yaml:5:15: error: `priority` expects an integer, got \"-0x80000001\""
        );
        assert_eq!(
            error(&skill("    priority: 0x80000000\n")),
            format!("robot.yaml:5:15: error: `priority` is out of range: {int32}, got 0x80000000")
        );
        assert_eq!(
            error("robot: r\ncycle: {threads: 0o777}\n"),
            "robot.yaml:2:18: error: `threads` is out of range: expects an integer from 1 to 64, got 0o777"
        );
    }
}
