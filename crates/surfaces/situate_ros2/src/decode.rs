//! Reading ROS 2 payloads (plain CDR, XCDR1) into the serde types of [`crate::msgs`] and
//! [`crate::services`], with every declared length checked against the bytes present before
//! anything is allocated (decision 0011).
//!
//! A payload is the 4-byte encapsulation header (`00 00` big endian, `00 01` little endian, then
//! two option bytes) and the body; a primitive is aligned to its size relative to the body's
//! start; a string is a `u32` length counting its terminating NUL, then the bytes and the NUL; a
//! sequence is a `u32` count, then the elements; a fixed array and a struct are their elements in
//! order. Bytes after the message are ignored, as ROS 2's readers do (writers may pad).
//!
//! The bounds: a string may declare no more bytes than are left; a sequence no more elements than
//! there are bytes left, since every element takes at least one byte (even an empty ROS 2
//! message carries a one-byte placeholder). A string is borrowed from the payload until the
//! message takes it (one allocation of its exact length), and a sequence is given no size hint,
//! so its vector grows with the elements actually read: what a payload can make the decoder
//! allocate is a small multiple of its length, whatever it declares.

use std::fmt;

use serde::de::{self, DeserializeSeed, Visitor};

/// Why a payload could not be read, and where.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("{}at byte {offset}: {problem}", field_prefix(.field))]
pub struct DecodeError {
    /// The byte of the payload (counting the encapsulation header) the problem was found at.
    pub offset: usize,
    /// The field being read, as a path (`parameters[0].value.string_value`); empty for the
    /// payload as a whole.
    pub field: String,
    pub problem: Problem,
}

fn field_prefix(field: &str) -> String {
    if field.is_empty() {
        String::new()
    } else {
        format!("`{field}` ")
    }
}

/// What is wrong with a payload.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum Problem {
    #[error("the payload is {len} bytes, too short for CDR's 4-byte encapsulation header")]
    NoHeader { len: usize },
    #[error("encapsulation {0:02x} {1:02x} is not plain CDR (00 00 big endian or 00 01 little endian)")]
    Encapsulation(u8, u8),
    #[error("{what} needs {need} {}, {left} left", if *need == 1 { "byte" } else { "bytes" })]
    Truncated { what: &'static str, need: usize, left: usize },
    #[error("a string declares {declared} bytes, {left} left")]
    StringTooLong { declared: u32, left: usize },
    #[error("a sequence declares {declared} elements, {left} bytes left (each element takes at least one)")]
    SequenceTooLong { declared: u32, left: usize },
    #[error("a string does not end in NUL")]
    NoTerminator,
    #[error("a string is not UTF-8: {0}")]
    Utf8(std::str::Utf8Error),
    #[error("a bool is {0}, neither 0 nor 1")]
    Bool(u8),
    #[error("{0} cannot be read from CDR (no ROS 2 message has one)")]
    Unsupported(&'static str),
    #[error("{0}")]
    Invalid(String),
}

/// An error on its way out of the serde machinery: the location is filled in by the innermost
/// field or element it passes (serde's own errors, `custom`, are made without one).
#[derive(Debug)]
struct Error {
    located: Option<(usize, String)>,
    problem: Problem,
}

impl fmt::Display for Error {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        self.problem.fmt(f)
    }
}

impl std::error::Error for Error {}

impl de::Error for Error {
    fn custom<T: fmt::Display>(msg: T) -> Self {
        Error { located: None, problem: Problem::Invalid(msg.to_string()) }
    }
}

/// Decodes a ROS 2 payload: the encapsulation header, then a `T`.
pub fn from_payload<'de, T: de::Deserialize<'de>>(payload: &'de [u8]) -> Result<T, DecodeError> {
    let Some(header) = payload.get(..4) else {
        return Err(DecodeError { offset: 0, field: String::new(), problem: Problem::NoHeader { len: payload.len() } });
    };
    let little = match (header[0], header[1]) {
        (0, 0) => false,
        (0, 1) => true,
        (a, b) => return Err(DecodeError { offset: 0, field: String::new(), problem: Problem::Encapsulation(a, b) }),
    };
    let mut reader = Reader { bytes: payload, pos: 4, little, path: Vec::new() };
    T::deserialize(&mut reader).map_err(|e| {
        let (offset, field) = e.located.unwrap_or_else(|| (reader.pos, reader.path_string()));
        DecodeError { offset, field, problem: e.problem }
    })
}

/// One step of the path to the field being read.
#[derive(Debug, Clone, Copy)]
enum Step {
    Field(&'static str),
    Index(usize),
}

struct Reader<'de> {
    bytes: &'de [u8],
    /// The next byte to read, from the payload's start (the body starts at 4).
    pos: usize,
    little: bool,
    path: Vec<Step>,
}

impl<'de> Reader<'de> {
    fn left(&self) -> usize {
        self.bytes.len() - self.pos
    }

    fn fail(&self, problem: Problem) -> Error {
        Error { located: Some((self.pos, self.path_string())), problem }
    }

    fn path_string(&self) -> String {
        let mut s = String::new();
        for step in &self.path {
            match step {
                Step::Field(name) => {
                    if !s.is_empty() {
                        s.push('.');
                    }
                    s.push_str(name);
                }
                Step::Index(i) => s.push_str(&format!("[{i}]")),
            }
        }
        s
    }

    /// Takes `n` bytes, or fails naming `what` they were for.
    fn take(&mut self, n: usize, what: &'static str) -> Result<&'de [u8], Error> {
        if n > self.left() {
            return Err(self.fail(Problem::Truncated { what, need: n, left: self.left() }));
        }
        let out = &self.bytes[self.pos..self.pos + n];
        self.pos += n;
        Ok(out)
    }

    /// Skips the padding before a primitive of `size` bytes (aligned relative to the body).
    fn align(&mut self, size: usize, what: &'static str) -> Result<(), Error> {
        let pad = (size - (self.pos - 4) % size) % size;
        self.take(pad, what).map(|_| ())
    }

    fn array<const N: usize>(&mut self, what: &'static str) -> Result<[u8; N], Error> {
        self.align(N, what)?;
        let mut out = [0; N];
        out.copy_from_slice(self.take(N, what)?);
        Ok(out)
    }

    fn u32(&mut self, what: &'static str) -> Result<u32, Error> {
        let b = self.array::<4>(what)?;
        Ok(if self.little { u32::from_le_bytes(b) } else { u32::from_be_bytes(b) })
    }

    /// A string's bytes, without the NUL, borrowed from the payload.
    fn string(&mut self) -> Result<&'de str, Error> {
        let declared = self.u32("a string's length")?;
        let len = declared as usize;
        if len > self.left() {
            return Err(self.fail(Problem::StringTooLong { declared, left: self.left() }));
        }
        let start = self.pos;
        let bytes = self.take(len, "a string")?;
        // Fast-CDR reads a length of 0 as the empty string; ROS 2's writers send 1 and a NUL.
        let text = match bytes.split_last() {
            None => &[][..],
            Some((0, text)) => text,
            Some(_) => {
                self.pos = start + len - 1;
                return Err(self.fail(Problem::NoTerminator));
            }
        };
        std::str::from_utf8(text).map_err(|e| {
            self.pos = start + e.valid_up_to();
            self.fail(Problem::Utf8(e))
        })
    }

    /// A sequence's element count, checked against the bytes left.
    fn count(&mut self) -> Result<usize, Error> {
        let declared = self.u32("a sequence's length")?;
        if declared as usize > self.left() {
            return Err(self.fail(Problem::SequenceTooLong { declared, left: self.left() }));
        }
        Ok(declared as usize)
    }
}

macro_rules! primitive {
    ($method:ident, $visit:ident, $ty:ty, $what:literal) => {
        fn $method<V: Visitor<'de>>(self, visitor: V) -> Result<V::Value, Error> {
            const N: usize = std::mem::size_of::<$ty>();
            let b = self.array::<N>($what)?;
            visitor.$visit(if self.little { <$ty>::from_le_bytes(b) } else { <$ty>::from_be_bytes(b) })
        }
    };
}

macro_rules! unsupported {
    ($($method:ident => $what:literal),* $(,)?) => {
        $(fn $method<V: Visitor<'de>>(self, _visitor: V) -> Result<V::Value, Error> {
            Err(self.fail(Problem::Unsupported($what)))
        })*
    };
}

impl<'de> de::Deserializer<'de> for &mut Reader<'de> {
    type Error = Error;

    primitive!(deserialize_i8, visit_i8, i8, "an int8");
    primitive!(deserialize_i16, visit_i16, i16, "an int16");
    primitive!(deserialize_i32, visit_i32, i32, "an int32");
    primitive!(deserialize_i64, visit_i64, i64, "an int64");
    primitive!(deserialize_u8, visit_u8, u8, "a uint8");
    primitive!(deserialize_u16, visit_u16, u16, "a uint16");
    primitive!(deserialize_u32, visit_u32, u32, "a uint32");
    primitive!(deserialize_u64, visit_u64, u64, "a uint64");
    primitive!(deserialize_f32, visit_f32, f32, "a float32");
    primitive!(deserialize_f64, visit_f64, f64, "a float64");

    unsupported! {
        deserialize_any => "a self-describing value",
        deserialize_option => "an optional value",
        deserialize_map => "a map",
        deserialize_identifier => "an identifier",
        deserialize_ignored_any => "an ignored value",
    }

    fn deserialize_bool<V: Visitor<'de>>(self, visitor: V) -> Result<V::Value, Error> {
        match self.take(1, "a bool")?[0] {
            0 => visitor.visit_bool(false),
            1 => visitor.visit_bool(true),
            b => {
                self.pos -= 1;
                Err(self.fail(Problem::Bool(b)))
            }
        }
    }

    /// ROS 2's `char` is one byte.
    fn deserialize_char<V: Visitor<'de>>(self, visitor: V) -> Result<V::Value, Error> {
        visitor.visit_char(char::from(self.take(1, "a char")?[0]))
    }

    fn deserialize_str<V: Visitor<'de>>(self, visitor: V) -> Result<V::Value, Error> {
        visitor.visit_borrowed_str(self.string()?)
    }

    fn deserialize_string<V: Visitor<'de>>(self, visitor: V) -> Result<V::Value, Error> {
        visitor.visit_borrowed_str(self.string()?)
    }

    fn deserialize_bytes<V: Visitor<'de>>(self, visitor: V) -> Result<V::Value, Error> {
        let n = self.count()?;
        visitor.visit_borrowed_bytes(self.take(n, "a byte sequence")?)
    }

    fn deserialize_byte_buf<V: Visitor<'de>>(self, visitor: V) -> Result<V::Value, Error> {
        self.deserialize_bytes(visitor)
    }

    fn deserialize_unit<V: Visitor<'de>>(self, visitor: V) -> Result<V::Value, Error> {
        visitor.visit_unit()
    }

    fn deserialize_unit_struct<V: Visitor<'de>>(self, _name: &'static str, visitor: V) -> Result<V::Value, Error> {
        visitor.visit_unit()
    }

    fn deserialize_newtype_struct<V: Visitor<'de>>(self, _name: &'static str, visitor: V) -> Result<V::Value, Error> {
        visitor.visit_newtype_struct(self)
    }

    fn deserialize_seq<V: Visitor<'de>>(self, visitor: V) -> Result<V::Value, Error> {
        let len = self.count()?;
        visitor.visit_seq(Elements { reader: self, next: 0, len, fields: None, hint: false })
    }

    /// A fixed-size array: its length is the type's, not on the wire.
    fn deserialize_tuple<V: Visitor<'de>>(self, len: usize, visitor: V) -> Result<V::Value, Error> {
        visitor.visit_seq(Elements { reader: self, next: 0, len, fields: None, hint: true })
    }

    fn deserialize_tuple_struct<V: Visitor<'de>>(
        self,
        _name: &'static str,
        len: usize,
        visitor: V,
    ) -> Result<V::Value, Error> {
        self.deserialize_tuple(len, visitor)
    }

    fn deserialize_struct<V: Visitor<'de>>(
        self,
        _name: &'static str,
        fields: &'static [&'static str],
        visitor: V,
    ) -> Result<V::Value, Error> {
        visitor.visit_seq(Elements { reader: self, next: 0, len: fields.len(), fields: Some(fields), hint: true })
    }

    fn deserialize_enum<V: Visitor<'de>>(
        self,
        _name: &'static str,
        _variants: &'static [&'static str],
        _visitor: V,
    ) -> Result<V::Value, Error> {
        Err(self.fail(Problem::Unsupported("an enum")))
    }

    fn is_human_readable(&self) -> bool {
        false
    }
}

/// The elements of a sequence, a fixed array or a struct, each read with its step on the path.
struct Elements<'a, 'de> {
    reader: &'a mut Reader<'de>,
    next: usize,
    len: usize,
    /// A struct's field names.
    fields: Option<&'static [&'static str]>,
    /// Whether `len` is the type's own (a struct, a fixed array) and may size a buffer; a
    /// sequence's count comes from the wire, so its vector grows with what is read instead.
    hint: bool,
}

impl<'de> de::SeqAccess<'de> for Elements<'_, 'de> {
    type Error = Error;

    fn next_element_seed<T: DeserializeSeed<'de>>(&mut self, seed: T) -> Result<Option<T::Value>, Error> {
        if self.next == self.len {
            return Ok(None);
        }
        let step = match self.fields {
            Some(names) => Step::Field(names[self.next]),
            None => Step::Index(self.next),
        };
        self.next += 1;
        self.reader.path.push(step);
        let value = seed.deserialize(&mut *self.reader).map_err(|mut e| {
            if e.located.is_none() {
                e.located = Some((self.reader.pos, self.reader.path_string()));
            }
            e
        });
        self.reader.path.pop();
        value.map(Some)
    }

    fn size_hint(&self) -> Option<usize> {
        self.hint.then_some(self.len - self.next)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::msgs::encode;
    use crate::services::{Names, Parameter, ParameterValue, SetParametersRequest};

    #[test]
    fn a_string_longer_than_the_payload_is_refused_before_it_is_read() {
        // A GetParameters request: one name declaring 4 GiB - 1 bytes, and none of them.
        let mut bytes = vec![0, 1, 0, 0];
        bytes.extend_from_slice(&1u32.to_le_bytes());
        bytes.extend_from_slice(&u32::MAX.to_le_bytes());
        let e = from_payload::<Names>(&bytes).expect_err("refused");
        assert_eq!(e.problem, Problem::StringTooLong { declared: u32::MAX, left: 0 });
        assert_eq!((e.offset, e.field.as_str()), (12, "names[0]"));
        assert_eq!(e.to_string(), "`names[0]` at byte 12: a string declares 4294967295 bytes, 0 left");
    }

    #[test]
    fn a_sequence_longer_than_the_bytes_left_is_refused() {
        let mut bytes = vec![0, 1, 0, 0];
        bytes.extend_from_slice(&0x4000_0000u32.to_le_bytes());
        bytes.extend_from_slice(&[0; 8]);
        let e = from_payload::<SetParametersRequest>(&bytes).expect_err("refused");
        assert_eq!(e.problem, Problem::SequenceTooLong { declared: 0x4000_0000, left: 8 });
        assert_eq!(e.field, "parameters");
    }

    #[test]
    fn what_the_cdr_crate_writes_reads_back_in_both_byte_orders() {
        let r = SetParametersRequest {
            parameters: vec![Parameter {
                name: "wander.speed".into(),
                value: ParameterValue {
                    ty: 9,
                    string_array_value: vec!["a".into(), String::new(), "äb".into()],
                    double_array_value: vec![0.5, -1.0],
                    bool_array_value: vec![true, false],
                    byte_array_value: vec![1, 2, 3],
                    ..ParameterValue::default()
                },
            }],
        };
        let le = encode(&r).expect("encodes");
        assert_eq!(from_payload::<SetParametersRequest>(&le), Ok(r.clone()));
        let be = cdr::serialize::<_, _, cdr::CdrBe>(&r, cdr::Infinite).expect("encodes");
        assert_eq!(&be[..2], &[0, 0]);
        assert_eq!(from_payload::<SetParametersRequest>(&be), Ok(r));
    }

    #[test]
    fn bad_payloads_are_named() {
        let e = from_payload::<Names>(&[0, 1]).expect_err("short");
        assert_eq!(e.problem, Problem::NoHeader { len: 2 });
        let e = from_payload::<Names>(&[0, 3, 0, 0, 0, 0, 0, 0]).expect_err("PL_CDR");
        assert_eq!(e.problem, Problem::Encapsulation(0, 3));
        let e = from_payload::<Names>(&[0, 1, 0, 0, 1, 0, 0]).expect_err("truncated count");
        assert_eq!(e.problem, Problem::Truncated { what: "a sequence's length", need: 4, left: 3 });
        // One name of 2 bytes without its NUL.
        let e = from_payload::<Names>(&[0, 1, 0, 0, 1, 0, 0, 0, 2, 0, 0, 0, b'a', b'b']).expect_err("no NUL");
        assert_eq!((e.problem, e.offset), (Problem::NoTerminator, 13));
        let e = from_payload::<Names>(&[0, 1, 0, 0, 1, 0, 0, 0, 2, 0, 0, 0, 0xff, 0]).expect_err("not UTF-8");
        assert!(matches!(e.problem, Problem::Utf8(_)) && e.offset == 12, "{e}");
        let e = from_payload::<crate::services::SetBoolRequest>(&[0, 1, 0, 0, 2]).expect_err("bool");
        assert_eq!(e.to_string(), "`data` at byte 4: a bool is 2, neither 0 nor 1");
    }
}
