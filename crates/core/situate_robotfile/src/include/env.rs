//! `${NAME}` substitution: a robot file's text with environment variables
//! put in, before it is parsed.

/// Looks an environment variable up: its value, `None` when unset.
pub type EnvLookup<'a> = &'a dyn Fn(&str) -> Option<String>;

/// Replaces `${NAME}` with the environment's value of NAME, and
/// `${NAME:-default}` with the default when NAME is unset or empty; `$${`
/// stays a literal `${`. Comment lines (`#` first) are left alone. An unset
/// NAME without a default is an error at its line and column (1-based).
pub fn substitute_env(source: &str, lookup: impl Fn(&str) -> Option<String>) -> Result<String, (usize, usize, String)> {
    if !source.contains("${") {
        return Ok(source.to_string());
    }
    let mut out = String::with_capacity(source.len());
    for (n, line) in source.split_inclusive('\n').enumerate() {
        if line.trim_start().starts_with('#') {
            out.push_str(line);
            continue;
        }
        let mut rest = line;
        while let Some(at) = rest.find("${") {
            if rest[..at].ends_with('$') {
                out.push_str(&rest[..at - 1]);
                out.push_str("${");
                rest = &rest[at + 2..];
                continue;
            }
            out.push_str(&rest[..at]);
            let col = line[..line.len() - rest.len() + at].chars().count() + 1;
            let Some(end) = rest[at..].find('}') else {
                return Err((n + 1, col, "`${` without its closing `}` (write `$${` for a literal `${`)".into()));
            };
            let inner = &rest[at + 2..at + end];
            let (name, default) = match inner.split_once(":-") {
                Some((name, default)) => (name, Some(default)),
                None => (inner, None),
            };
            let valid = !name.is_empty()
                && name.chars().all(|c| c.is_ascii_alphanumeric() || c == '_')
                && !name.starts_with(|c: char| c.is_ascii_digit());
            if !valid {
                return Err((n + 1, col, format!("`${{{inner}}}`: `{name}` is not an environment variable's name")));
            }
            match (lookup(name).filter(|v| !v.is_empty()), default) {
                (Some(value), _) => out.push_str(&value),
                (None, Some(default)) => out.push_str(default),
                (None, None) => {
                    return Err((
                        n + 1,
                        col,
                        format!("`${{{name}}}`: the environment variable `{name}` is not set (give a default: `${{{name}:-value}}`)"),
                    ))
                }
            }
            rest = &rest[at + end + 1..];
        }
        out.push_str(rest);
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn substitution_counts_columns_in_characters() {
        let env = |name: &str| (name == "A").then(|| "1".to_string());
        assert_eq!(substitute_env("x: ${A}\n", env), Ok("x: 1\n".to_string()));
        let e = substitute_env("é: ${B}\n", env).expect_err("B is unset");
        assert_eq!((e.0, e.1), (1, 4));
        assert_eq!(substitute_env("# ${B}\nx: $${B}\n", env), Ok("# ${B}\nx: ${B}\n".to_string()));
    }
}
