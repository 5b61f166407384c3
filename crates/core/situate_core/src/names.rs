//! Names: "did you mean" suggestions for error messages.

/// The candidate closest to `name`, if it is close enough to be a likely
/// typo (`wandr` → `wander`).
pub fn did_you_mean<'a, I>(name: &str, candidates: I) -> Option<&'a str>
where
    I: IntoIterator<Item = &'a str>,
{
    let len = name.chars().count();
    let limit = (len / 3).max(1);
    candidates
        .into_iter()
        // Lengths further apart than the limit are further apart in edits:
        // skip them without the quadratic distance (a name of a million
        // characters stays cheap).
        .filter(|c| len.abs_diff(c.chars().count()) <= limit)
        .map(|c| (edit_distance(name, c), c))
        .filter(|(d, _)| *d <= limit)
        .min_by_key(|(d, _)| *d)
        .map(|(_, c)| c)
}

/// `" — did you mean `x`?"` or an empty string; ready to append to a message.
pub fn suggestion<'a, I>(name: &str, candidates: I) -> String
where
    I: IntoIterator<Item = &'a str>,
{
    did_you_mean(name, candidates).map(|c| format!(" — did you mean `{c}`?")).unwrap_or_default()
}

/// For an unknown parameter: `" — did you mean `x`?"` when one is close, else the parameters
/// there are (`" (its parameters: `a`, `b`)"`, or `" (it has no parameters)"`), so that the
/// message always says what would be right.
pub fn param_suggestion<'a, I>(name: &str, params: I) -> String
where
    I: IntoIterator<Item = &'a str> + Clone,
{
    if let Some(close) = did_you_mean(name, params.clone()) {
        return format!(" — did you mean `{close}`?");
    }
    let all: Vec<String> = params.into_iter().map(|p| format!("`{p}`")).collect();
    if all.is_empty() {
        " (it has no parameters)".to_string()
    } else {
        format!(" (its parameters: {})", all.join(", "))
    }
}

/// Edit distance over chars counting a swap of two neighbours as one edit
/// (optimal string alignment), so `levle` is one edit from `level`.
pub fn edit_distance(a: &str, b: &str) -> usize {
    let a: Vec<char> = a.chars().collect();
    let b: Vec<char> = b.chars().collect();
    let mut d = vec![vec![0usize; b.len() + 1]; a.len() + 1];
    for (i, row) in d.iter_mut().enumerate() {
        row[0] = i;
    }
    for (j, cell) in d[0].iter_mut().enumerate() {
        *cell = j;
    }
    for i in 1..=a.len() {
        for j in 1..=b.len() {
            let cost = usize::from(a[i - 1] != b[j - 1]);
            let mut best = (d[i - 1][j] + 1).min(d[i][j - 1] + 1).min(d[i - 1][j - 1] + cost);
            if i > 1 && j > 1 && a[i - 1] == b[j - 2] && a[i - 2] == b[j - 1] {
                best = best.min(d[i - 2][j - 2] + 1);
            }
            d[i][j] = best;
        }
    }
    d[a.len()][b.len()]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn an_unknown_parameter_gets_the_close_one_or_the_list() {
        let params = ["safe_distance", "speed"];
        assert_eq!(param_suggestion("safe_distnce", params), " — did you mean `safe_distance`?");
        assert_eq!(param_suggestion("x", params), " (its parameters: `safe_distance`, `speed`)");
        assert_eq!(param_suggestion("x", []), " (it has no parameters)");
    }

    #[test]
    fn suggests_close_names_only() {
        let names = ["wander", "runaway", "sonar"];
        assert_eq!(did_you_mean("wandr", names), Some("wander"));
        assert_eq!(did_you_mean("runaway", names), Some("runaway"));
        assert_eq!(did_you_mean("elevator", names), None);
        assert_eq!(suggestion("sonr", names), " — did you mean `sonar`?");
        assert_eq!(edit_distance("levle", "level"), 1);
        assert_eq!(did_you_mean("levle", ["level", "label"]), Some("level"));
        assert_eq!(did_you_mean(&"x".repeat(1_000_000), names), None);
    }
}
