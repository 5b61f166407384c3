//! A recording being read: the MCAP file's structure walked (header, data section, chunks
//! decompressed within bounds, CRCs, summary, footer) and its schemas, channels and messages
//! taken in.

use std::borrow::Cow;
use std::collections::HashMap;

use mcap::records::{op, Record};

use super::records::{record_name, records};
use super::{ReadError, Recording, MAX_CHUNK_BYTES, MAX_UNCOMPRESSED_BYTES};

/// A recording being read.
pub(super) struct Reader {
    pub(super) rec: Recording,
    /// Channel id → topic.
    pub(super) channels: HashMap<u16, String>,
    pub(super) chunks: u64,
    /// Bytes decompressed so far.
    pub(super) uncompressed: u64,
    /// `situate/gaps` markers: (first, last).
    pub(super) gaps: Vec<(u64, u64)>,
    /// The `situate_drops` record: how many, which.
    pub(super) drops: Option<(u64, Vec<(u64, u64)>)>,
    pub(super) statistics: Option<mcap::records::Statistics>,
    /// Whether a file cut short is read up to where it ends.
    pub(super) recover: bool,
    /// Where such a file ended: (byte, why, whether its data section was whole).
    pub(super) cut: Option<(usize, String, bool)>,
}

impl Reader {
    pub(super) fn bad(&self, message: String) -> ReadError {
        ReadError::Bad { path: self.rec.path.clone(), message }
    }

    /// Walks the file's records: header, data section, data end, summary,
    /// footer, magic.
    pub(super) fn read(&mut self, bytes: &[u8]) -> Result<(), ReadError> {
        if bytes.len() < mcap::MAGIC.len() || &bytes[..mcap::MAGIC.len()] != mcap::MAGIC {
            return Err(self.bad("not an MCAP file: it does not start with the MCAP magic bytes".into()));
        }
        // Where the data section ends and the summary starts, once seen.
        let mut summary_start: Option<usize> = None;
        // Where the records read so far end (a file cut short ends there).
        let mut end = mcap::MAGIC.len();
        for record in records(bytes, mcap::MAGIC.len()) {
            let (k, at, opcode, body) = match record {
                Ok(r) => r,
                Err(m) if self.recover => {
                    self.cut = Some((end, m, summary_start.is_some()));
                    return Ok(());
                }
                Err(m) => {
                    return Err(self
                        .bad(format!("{m}: the file is cut short or damaged (--recover reads the cycles before it)")))
                }
            };
            // A power cut leaves blocks of zeros where the last writes were to go.
            if self.recover && opcode == 0 && bytes[at..].iter().all(|&b| b == 0) {
                let reason = format!("the rest of the file, {} bytes from byte {at}, is zeros", bytes.len() - at);
                self.cut = Some((at, reason, summary_start.is_some()));
                return Ok(());
            }
            end = at + 9 + body.len();
            let place = || format!("record {k} at byte {at} ({})", record_name(opcode));
            let parse = |this: &Self| {
                mcap::parse_record(opcode, body).map_err(|e| this.bad(format!("{}: {e}: a damaged file", place())))
            };
            if k == 0 && opcode != op::HEADER {
                return Err(self.bad(format!("{}: the file does not begin with an MCAP header", place())));
            }
            match opcode {
                op::HEADER if k == 0 => {}
                op::SCHEMA | op::CHANNEL | op::MESSAGE => {
                    let record = parse(self)?;
                    self.inner(record, &place())?;
                }
                op::CHUNK if summary_start.is_none() => self.chunk(body, &place())?,
                op::METADATA => {
                    if let Record::Metadata(m) = parse(self)? {
                        self.metadata(m)?;
                    }
                }
                op::STATISTICS => {
                    if let Record::Statistics(s) = parse(self)? {
                        self.statistics = Some(s);
                    }
                }
                op::MESSAGE_INDEX
                | op::CHUNK_INDEX
                | op::ATTACHMENT
                | op::ATTACHMENT_INDEX
                | op::METADATA_INDEX
                | op::SUMMARY_OFFSET => {}
                op::DATA_END if summary_start.is_none() => {
                    if let Record::DataEnd(end) = parse(self)? {
                        let computed = crc32fast::hash(&bytes[..at]);
                        if end.data_section_crc != 0 && end.data_section_crc != computed {
                            return Err(self.bad(format!(
                                "{}: the data section's CRC is {:08x}, the file's says {:08x}: the file was changed \
                                 or damaged after it was written",
                                place(),
                                computed,
                                end.data_section_crc
                            )));
                        }
                    }
                    summary_start = Some(at + 9 + body.len());
                }
                op::FOOTER => {
                    let Some(start) = summary_start else {
                        return Err(self.bad(format!("{}: a footer before the data end record", place())));
                    };
                    if let Record::Footer(footer) = parse(self)? {
                        // Over the summary section and the footer up to its CRC.
                        let end = at + 9 + 16;
                        if footer.summary_crc != 0 && end <= bytes.len() {
                            let computed = crc32fast::hash(&bytes[start..end]);
                            if computed != footer.summary_crc {
                                return Err(self.bad(format!(
                                    "{}: the summary's CRC is {:08x}, the footer says {:08x}: a damaged summary",
                                    place(),
                                    computed,
                                    footer.summary_crc
                                )));
                            }
                        }
                    }
                    let tail = &bytes[at + 9 + body.len()..];
                    if tail != mcap::MAGIC {
                        return Err(self.bad(format!(
                            "byte {}: the file does not end with the MCAP magic bytes after its footer: cut short or \
                             damaged",
                            at + 9 + body.len()
                        )));
                    }
                    return Ok(());
                }
                _ => return Err(self.bad(format!("{}: not a record a recording holds here: a damaged file", place()))),
            }
        }
        let missing = if summary_start.is_some() { "footer" } else { "data end record, summary and footer" };
        if self.recover {
            // The data section was read whole when the summary began: only the
            // index is lost, and nothing of the run.
            self.cut = Some((end, format!("the file ends without its {missing}"), summary_start.is_some()));
            return Ok(());
        }
        Err(self.bad(format!(
            "the file ends at byte {} without its {missing}: it was cut short (a recording that was not finished, \
             such as a robot killed while recording; --recover reads the cycles it holds)",
            bytes.len(),
        )))
    }

    /// A chunk: its header checked, decompressed (bounded), its CRC
    /// checked, its records read.
    fn chunk(&mut self, body: &[u8], place: &str) -> Result<(), ReadError> {
        let (header, data) = match mcap::parse_record(op::CHUNK, body) {
            Ok(Record::Chunk { header, data }) => (header, data),
            Ok(_) => return Err(self.bad(format!("{place}: not a chunk"))),
            Err(e) => return Err(self.bad(format!("{place}: {e}: a damaged chunk header"))),
        };
        let header_len = 8 + 8 + 8 + 4 + 4 + header.compression.len() + 8;
        let held = body.len().saturating_sub(header_len) as u64;
        if header.compressed_size != held {
            return Err(self.bad(format!(
                "{place}: its header says {} compressed bytes, the record holds {held}: a damaged chunk header",
                header.compressed_size
            )));
        }
        if header.uncompressed_crc == 0 {
            return Err(self.bad(format!(
                "{place}: its header has no CRC (situate writes one in every chunk): a damaged chunk header"
            )));
        }
        if header.uncompressed_size > MAX_CHUNK_BYTES {
            return Err(self.bad(format!(
                "{place}: its header says {} bytes uncompressed, more than the {MAX_CHUNK_BYTES} a chunk may hold \
                 (situate writes about 1 MiB): a damaged chunk header",
                header.uncompressed_size
            )));
        }
        self.uncompressed += header.uncompressed_size;
        if self.uncompressed > MAX_UNCOMPRESSED_BYTES {
            return Err(self.bad(format!(
                "{place}: the chunks so far hold more than {MAX_UNCOMPRESSED_BYTES} bytes uncompressed, more than a \
                 recording is read up to"
            )));
        }
        let content: Cow<'_, [u8]> = match header.compression.as_str() {
            "zstd" => Cow::Owned(
                zstd::bulk::decompress(&data, header.uncompressed_size as usize)
                    .map_err(|e| self.bad(format!("{place}: cannot be decompressed ({e}): a damaged chunk")))?,
            ),
            "" => data,
            other => {
                return Err(self.bad(format!("{place}: compressed with `{other}`; situate writes zstd (or nothing)")))
            }
        };
        if content.len() as u64 != header.uncompressed_size {
            return Err(self.bad(format!(
                "{place}: it holds {} bytes uncompressed, its header says {}: a damaged chunk",
                content.len(),
                header.uncompressed_size
            )));
        }
        let crc = crc32fast::hash(&content);
        if crc != header.uncompressed_crc {
            return Err(self.bad(format!(
                "{place}: its CRC is {crc:08x}, its header says {:08x}: a damaged chunk",
                header.uncompressed_crc
            )));
        }
        self.chunks += 1;
        for record in records(&content, 0) {
            let (k, at, opcode, body) =
                record.map_err(|m| self.bad(format!("{place}, its {m} of its records: a damaged chunk")))?;
            let inner = || format!("{place}, its record {k} at byte {at} of its records ({})", record_name(opcode));
            if !matches!(opcode, op::SCHEMA | op::CHANNEL | op::MESSAGE) {
                return Err(self.bad(format!("{}: not a record a chunk holds: a damaged chunk", inner())));
            }
            let record =
                mcap::parse_record(opcode, body).map_err(|e| self.bad(format!("{}: {e}: a damaged chunk", inner())))?;
            self.inner(record, &inner())?;
        }
        Ok(())
    }

    /// A schema, a channel or a message.
    fn inner(&mut self, record: Record<'_>, place: &str) -> Result<(), ReadError> {
        match record {
            Record::Channel(c) => {
                if let Some(topic) = self.channels.get(&c.id) {
                    if *topic != c.topic {
                        return Err(self.bad(format!(
                            "{place}: channel {} is `{}` here and `{topic}` before: a damaged file",
                            c.id, c.topic
                        )));
                    }
                }
                self.channels.insert(c.id, c.topic);
            }
            Record::Message { header, data } => {
                self.rec.messages += 1;
                let Some(topic) = self.channels.get(&header.channel_id).cloned() else {
                    return Err(self.bad(format!(
                        "{place}: a message on channel {}, which no channel record before it defines: a damaged file",
                        header.channel_id
                    )));
                };
                self.message(&topic, header.log_time, &data, place)?;
            }
            _ => {}
        }
        Ok(())
    }
}
