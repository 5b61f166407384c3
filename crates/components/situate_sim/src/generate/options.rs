//! The generator's options (`situate map generate`'s flags): each a range
//! the seed draws from, checked against its bounds (those of `situate map
//! check`'s rules where there is one), and `A..B` parsed as a range.

use thiserror::Error;

/// The generator's options: each a range the seed draws from.
#[derive(Debug, Clone, PartialEq)]
pub struct Options {
    /// Floors in all (start, lobbies in between, goal): 2..=6.
    pub floors: (i64, i64),
    /// Elevator cars: 1..=4.
    pub cars: (i64, i64),
    /// Corridor width, m: within 1.8..=3.0.
    pub corridor_width: (f64, f64),
    /// Door width (lab, rooms, office, cars), m: within 0.8..=1.6.
    pub door_width: (f64, f64),
    /// Junctions on the start floor's way to the lobby (the last one turns
    /// towards the lobby): 1..=3.
    pub junctions: (i64, i64),
    /// Clutter boxes per metre of corridor wall (0..=1); `None`: drawn in 0..=0.3.
    pub clutter: Option<f64>,
    /// The elevator's `open_s`; `None`: drawn from [8, 12] … [15, 25].
    pub open_s: Option<(f64, f64)>,
    /// A door barcode's distance from the nearer jamb, m: within 0.05..=1.0.
    pub barcode_offset: (f64, f64),
    /// Write the route hints.
    pub route: bool,
    /// The family of buildings: 2 (the default) draws from the whole space the
    /// docs allow; 1 is the family before issue 37, frozen (the same seed, the
    /// same building as then).
    pub family: u32,
}

impl Default for Options {
    fn default() -> Options {
        Options {
            floors: (2, 6),
            cars: (1, 4),
            corridor_width: (1.8, 2.6),
            door_width: (1.0, 1.4),
            junctions: (1, 3),
            clutter: None,
            open_s: None,
            barcode_offset: (0.1, 0.6),
            route: true,
            family: 2,
        }
    }
}

/// Options out of range, or no building found.
#[derive(Debug, Error)]
pub enum GenError {
    #[error("--{option}: {message}")]
    Option { option: &'static str, message: String },
    #[error("seed {seed}: no building passed `map check` in {attempts} attempts (the last: {last})")]
    NoLayout { seed: u64, attempts: usize, last: String },
}

/// Parses `A..B` (or `A`, meaning `A..A`) as a range of numbers.
pub fn parse_range(text: &str) -> Result<(f64, f64), String> {
    let num = |s: &str| -> Result<f64, String> {
        s.trim().parse::<f64>().ok().filter(|x| x.is_finite()).ok_or_else(|| format!("`{s}` is not a number"))
    };
    let (lo, hi) = match text.split_once("..") {
        Some((a, b)) => (num(a)?, num(b.trim_start_matches('='))?),
        None => {
            let x = num(text)?;
            (x, x)
        }
    };
    if lo > hi {
        return Err(format!("`{text}`: the minimum is above the maximum"));
    }
    Ok((lo, hi))
}

/// [`parse_range`] of whole numbers.
pub fn parse_int_range(text: &str) -> Result<(i64, i64), String> {
    let (lo, hi) = parse_range(text)?;
    if lo.fract() != 0.0 || hi.fract() != 0.0 {
        return Err(format!("`{text}`: expected whole numbers"));
    }
    Ok((lo as i64, hi as i64))
}

impl Options {
    /// Checks every option against its bounds.
    pub fn validate(&self) -> Result<(), GenError> {
        fn within<T: PartialOrd + std::fmt::Display + Copy>(
            option: &'static str,
            (lo, hi): (T, T),
            min: T,
            max: T,
        ) -> Result<(), GenError> {
            if lo > hi || lo < min || hi > max {
                return Err(GenError::Option { option, message: format!("{lo}..{hi} is not within {min}..{max}") });
            }
            Ok(())
        }
        within("family", (self.family, self.family), 1, 2)?;
        within("floors", self.floors, 2, 6)?;
        within("cars", self.cars, 1, 4)?;
        within("corridor-width", self.corridor_width, 1.8, 3.0)?;
        // `situate map check`'s rules (docs/maps.md): a building outside them is never drawn, so
        // options outside them are refused here, with the range, not after 50 failed attempts.
        within("door-width", self.door_width, crate::check::DOOR_MIN, crate::check::DOOR_MAX)?;
        within("junctions", self.junctions, 1, 3)?;
        // The rule `situate map check` holds maps to (docs/maps.md, "Lab door").
        within("barcode-offset", self.barcode_offset, 0.1, 0.6)?;
        if let Some(c) = self.clutter {
            within("clutter", (c, c), 0.0, 1.0)?;
        }
        if let Some(o) = self.open_s {
            within("open-s", o, crate::check::OPEN_S_MIN, 600.0)?;
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn options_outside_map_checks_rules_are_refused_with_the_range() {
        let refused = |opts: Options| match opts.validate() {
            Err(GenError::Option { option, message }) => format!("{option}: {message}"),
            other => panic!("accepted: {other:?}"),
        };
        let doors = Options { door_width: (0.8, 1.2), ..Options::default() };
        assert_eq!(refused(doors), "door-width: 0.8..1.2 is not within 1..1.4");
        let open = Options { open_s: Some((2.0, 3.0)), ..Options::default() };
        assert_eq!(refused(open), "open-s: 2..3 is not within 8..600");
        let edges = Options { door_width: (1.0, 1.4), open_s: Some((8.0, 12.0)), ..Options::default() };
        assert!(edges.validate().is_ok());
    }

    #[test]
    fn ranges_parse() {
        assert_eq!(parse_range("1.8..2.6"), Ok((1.8, 2.6)));
        assert_eq!(parse_range("2"), Ok((2.0, 2.0)));
        assert_eq!(parse_int_range("1..=3"), Ok((1, 3)));
        assert!(parse_range("3..2").is_err());
        assert!(parse_int_range("1.5").is_err());
        assert!(parse_range("x").is_err());
    }
}
