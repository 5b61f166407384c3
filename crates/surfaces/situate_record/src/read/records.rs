//! The MCAP file's records, one by one, each checked against the bytes present, and their
//! names for messages.

use mcap::records::op;

/// A record's name, for messages.
pub(super) fn record_name(opcode: u8) -> String {
    let name = match opcode {
        op::HEADER => "header",
        op::FOOTER => "footer",
        op::SCHEMA => "schema",
        op::CHANNEL => "channel",
        op::MESSAGE => "message",
        op::CHUNK => "chunk",
        op::MESSAGE_INDEX => "message index",
        op::CHUNK_INDEX => "chunk index",
        op::ATTACHMENT => "attachment",
        op::ATTACHMENT_INDEX => "attachment index",
        op::STATISTICS => "statistics",
        op::METADATA => "metadata",
        op::METADATA_INDEX => "metadata index",
        op::SUMMARY_OFFSET => "summary offset",
        op::DATA_END => "data end",
        _ => return format!("unknown record type 0x{opcode:02x}"),
    };
    name.to_string()
}

/// One record of a run of records: its number in the run, where it starts
/// (in the run's bytes), its opcode and body; an error saying which record
/// the bytes end inside.
pub(super) fn records(bytes: &[u8], start: usize) -> impl Iterator<Item = Result<(u64, usize, u8, &[u8]), String>> {
    let mut pos = start;
    let mut k = 0u64;
    std::iter::from_fn(move || {
        if pos >= bytes.len() {
            return None;
        }
        let at = pos;
        let left = bytes.len() - pos;
        if left < 9 {
            pos = bytes.len();
            return Some(Err(format!("record {k} at byte {at}: the bytes end inside its header ({left} of 9 bytes)")));
        }
        let opcode = bytes[pos];
        let mut len_bytes = [0u8; 8];
        len_bytes.copy_from_slice(&bytes[pos + 1..pos + 9]);
        let len = u64::from_le_bytes(len_bytes);
        let avail = (left - 9) as u64;
        if len > avail {
            pos = bytes.len();
            return Some(Err(format!(
                "record {k} at byte {at} ({}): its length, {len} bytes, runs past the end ({avail} bytes left)",
                record_name(opcode)
            )));
        }
        let body = &bytes[pos + 9..pos + 9 + len as usize];
        pos += 9 + len as usize;
        k += 1;
        Some(Ok((k - 1, at, opcode, body)))
    })
}
