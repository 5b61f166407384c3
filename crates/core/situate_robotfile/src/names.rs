//! What a name in a robot file may be: the robot's, an entry's, a port's, a
//! signal's.

/// `[A-Za-z_][A-Za-z0-9_]*`
pub fn is_identifier(s: &str) -> bool {
    let mut chars = s.chars();
    chars.next().is_some_and(|c| c.is_ascii_alphabetic() || c == '_')
        && chars.all(|c| c.is_ascii_alphanumeric() || c == '_')
}

/// Identifiers joined by dots: `sonar.range`.
pub fn is_signal_name(s: &str) -> bool {
    s.split('.').all(is_identifier)
}

/// `[A-Za-z0-9_-]+`
pub fn is_robot_name(s: &str) -> bool {
    !s.is_empty() && s.chars().all(|c| c.is_ascii_alphanumeric() || c == '_' || c == '-')
}
