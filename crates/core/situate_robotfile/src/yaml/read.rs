//! Reading a YAML source file as text: capped in size, UTF-8 only, with
//! the place of an invalid byte.

use super::Pos;

/// Why a YAML source file could not be read as text.
#[derive(Debug, thiserror::Error)]
pub enum ReadError {
    /// The file cannot be opened or read.
    #[error("cannot read {what}: {source}")]
    Io {
        what: &'static str,
        #[source]
        source: std::io::Error,
    },
    /// The file is larger than its cap (`size` is `None` when only "more
    /// than the cap" is known: the reader stopped there).
    #[error("the file is {}; a {what} may be at most {}", size.map_or(format!("more than {}", bytes(*max)), bytes), bytes(*max))]
    TooLarge { what: &'static str, size: Option<u64>, max: u64 },
    /// A byte sequence that is not UTF-8, at `pos`.
    #[error("invalid UTF-8 (byte 0x{byte:02X}): a {what} is UTF-8 text; save it as UTF-8")]
    NotUtf8 { what: &'static str, pos: Pos, byte: u8 },
    /// The file starts with a UTF-16 byte-order mark.
    #[error("the file is UTF-16 text; a {what} is UTF-8 text: save it as UTF-8")]
    Utf16 { what: &'static str },
}

impl ReadError {
    /// Where in the file the problem is; `None` for the file as a whole.
    pub fn pos(&self) -> Option<Pos> {
        match self {
            ReadError::NotUtf8 { pos, .. } => Some(*pos),
            _ => None,
        }
    }
}

/// "1048576 bytes (1 MiB)".
fn bytes(n: u64) -> String {
    const MIB: u64 = 1 << 20;
    match n {
        n if n >= MIB && n % MIB == 0 => format!("{n} bytes ({} MiB)", n / MIB),
        n if n >= MIB => format!("{n} bytes ({:.1} MiB)", n as f64 / MIB as f64),
        n => format!("{n} bytes"),
    }
}

/// Reads a YAML source file (a `what`: "robot file", "map file", …) of at
/// most `max` bytes as UTF-8 text. A larger file is refused by its size
/// before it is read, and the reader never takes more than `max + 1` bytes
/// (a file that grows, a pipe, a device). Invalid UTF-8 is an error at its
/// line and column.
pub fn read_source(path: &std::path::Path, what: &'static str, max: u64) -> Result<String, ReadError> {
    use std::io::Read;
    let io = |source| ReadError::Io { what, source };
    let file = std::fs::File::open(path).map_err(io)?;
    let meta = file.metadata().map_err(io)?;
    if meta.is_file() && meta.len() > max {
        return Err(ReadError::TooLarge { what, size: Some(meta.len()), max });
    }
    let mut buf = Vec::new();
    file.take(max.saturating_add(1)).read_to_end(&mut buf).map_err(io)?;
    if buf.len() as u64 > max {
        return Err(ReadError::TooLarge { what, size: None, max });
    }
    if buf.starts_with(&[0xff, 0xfe]) || buf.starts_with(&[0xfe, 0xff]) {
        return Err(ReadError::Utf16 { what });
    }
    String::from_utf8(buf).map_err(|e| {
        let at = e.utf8_error().valid_up_to();
        let bytes = e.as_bytes();
        let valid = std::str::from_utf8(&bytes[..at]).unwrap_or_default();
        let line = valid.matches('\n').count() + 1;
        let col = valid.rsplit('\n').next().unwrap_or_default().chars().count() + 1;
        ReadError::NotUtf8 { what, pos: Pos::new(line, col), byte: bytes[at] }
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn p(line: usize, col: usize) -> Pos {
        Pos::new(line, col)
    }

    #[test]
    fn read_source_stops_at_its_cap() {
        // A device that never ends is refused after cap + 1 bytes, not read on.
        #[cfg(unix)]
        {
            let e = read_source(std::path::Path::new("/dev/zero"), "test file", 16).unwrap_err();
            assert_eq!(e.to_string(), "the file is more than 16 bytes; a test file may be at most 16 bytes");
            assert_eq!(e.pos(), None);
        }
        let path = std::env::temp_dir().join(format!("situate-yaml-read-{}.yaml", std::process::id()));
        std::fs::write(&path, [b"a: \xc3\xa9\nbc: ".as_slice(), &[0xff]].concat()).unwrap();
        let e = read_source(&path, "robot file", 1 << 20).unwrap_err();
        assert_eq!(e.pos(), Some(p(2, 5)));
        std::fs::write(&path, "a: é\n").unwrap();
        assert_eq!(read_source(&path, "robot file", 6).unwrap(), "a: é\n");
        assert!(matches!(read_source(&path, "robot file", 5), Err(ReadError::TooLarge { size: Some(6), .. })));
        let _ = std::fs::remove_file(&path);
    }
}
