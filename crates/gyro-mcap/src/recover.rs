//! Recovery of a killed run: everything in a `.partial` file up to its last whole chunk, rewritten
//! as a valid, indexed recording.

use std::collections::HashMap;
use std::path::{Path, PathBuf};

use crate::error::{ParseError, RecordingError, io_error};
use crate::format::{
    Cursor, MAGIC, RawRecord, decompress_chunk, op, parse_attachment, parse_channel, parse_chunk,
    parse_message, parse_metadata, parse_schema,
};
use crate::writer::{McapWriter, WriterOptions, partial_path};

/// What [`recover`] kept and dropped.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct RecoverReport {
    pub out: PathBuf,
    /// Messages written to `out`.
    pub messages: u64,
    /// Whole chunks kept.
    pub chunks: u64,
    /// Bytes of the input after the last record kept (the torn tail).
    pub bytes_dropped: u64,
    /// Why reading stopped: `None` when the data section ended normally, else the error there.
    pub stopped_because: Option<String>,
}

struct Recoverer {
    mcap: McapWriter,
    schema_ids: HashMap<u16, u16>,
    chunks: u64,
}

impl Recoverer {
    fn schema(&mut self, r: &RawRecord) -> Result<Result<(), ParseError>, RecordingError> {
        let s = match parse_schema(r) {
            Ok(s) => s,
            Err(e) => return Ok(Err(e)),
        };
        if s.id != 0 && !self.schema_ids.contains_key(&s.id) {
            let new = self.mcap.add_schema(&s.name, &s.encoding, &s.data)?;
            self.schema_ids.insert(s.id, new);
        }
        Ok(Ok(()))
    }

    fn channel(&mut self, r: &RawRecord) -> Result<Result<(), ParseError>, RecordingError> {
        let c = match parse_channel(r) {
            Ok(c) => c,
            Err(e) => return Ok(Err(e)),
        };
        if self.mcap.slot_of(c.id).is_some() {
            return Ok(Ok(()));
        }
        let schema_id = if c.schema_id == 0 {
            0
        } else {
            match self.schema_ids.get(&c.schema_id) {
                Some(&id) => id,
                // A channel whose schema never arrived: its messages cannot be decoded; drop it.
                None => return Ok(Ok(())),
            }
        };
        self.mcap
            .add_channel(c.id, schema_id, &c.topic, &c.message_encoding, &c.metadata)?;
        Ok(Ok(()))
    }

    fn message(&mut self, r: &RawRecord) -> Result<(), RecordingError> {
        if let Ok(m) = parse_message(r)
            && let Some(slot) = self.mcap.slot_of(m.channel_id)
        {
            self.mcap
                .write_raw(slot, m.sequence, m.log_time, m.publish_time, m.data)?;
        }
        Ok(())
    }

    /// A chunk is kept only if it decompresses, its CRC matches and every record inside parses.
    fn chunk(
        &mut self,
        r: &RawRecord,
        buf: &mut Vec<u8>,
    ) -> Result<Result<(), ParseError>, RecordingError> {
        let checked = parse_chunk(r).and_then(|chunk| {
            decompress_chunk(&chunk, r.offset, buf)?;
            let mut c = Cursor::new(buf, 0, "chunk records");
            let mut records = Vec::new();
            while !c.is_empty() {
                let inner = c
                    .record()
                    .map_err(|e| ParseError::new(r.offset, "chunk", e.expected))?;
                if inner.opcode == op::MESSAGE {
                    parse_message(&inner)
                        .map_err(|e| ParseError::new(r.offset, "chunk", e.expected))?;
                }
                records.push((inner.opcode, inner.offset as usize..inner.end() as usize));
            }
            Ok(records)
        });
        let records = match checked {
            Ok(records) => records,
            Err(e) => return Ok(Err(e)),
        };
        self.mcap.close_chunk()?;
        for (opcode, range) in records {
            let body_start = range.start + 9;
            let raw = RawRecord {
                opcode,
                offset: range.start as u64,
                body: &buf[body_start..range.end],
                body_offset: body_start as u64,
            };
            let step = match opcode {
                op::SCHEMA => self.schema(&raw)?,
                op::CHANNEL => self.channel(&raw)?,
                op::MESSAGE => self.message(&raw).map(Ok)?,
                _ => Ok(()),
            };
            if let Err(e) = step {
                return Ok(Err(ParseError::new(r.offset, "chunk", e.expected)));
            }
        }
        self.mcap.close_chunk()?;
        self.chunks += 1;
        Ok(Ok(()))
    }
}

/// Reads `partial` (a recording whose writer was killed, or any MCAP file) up to the last record
/// that is whole (a chunk counts only if it decompresses and checks), and writes everything kept
/// (schemas, channels, metadata, attachments, messages with their original chunking) to `out` as
/// a finished, indexed recording.
pub fn recover(partial: &Path, out: &Path) -> Result<RecoverReport, RecordingError> {
    let data = std::fs::read(partial).map_err(io_error(partial, "reading"))?;
    if data.len() < MAGIC.len() || &data[..MAGIC.len()] != MAGIC {
        return Err(
            ParseError::new(0, "file start", "the MCAP magic (this is not an MCAP file)")
                .in_file(partial),
        );
    }
    let mut c = Cursor::new(&data[MAGIC.len()..], MAGIC.len() as u64, "data section");
    match c.record() {
        Ok(r) if r.opcode == op::HEADER => {}
        _ => {
            return Err(ParseError::new(
                MAGIC.len() as u64,
                "header",
                "a header record after the magic",
            )
            .in_file(partial));
        }
    }
    let defaults = WriterOptions::default();
    let tmp = temp_path(partial, out);
    let result = recover_into(c, partial, &tmp, defaults);
    let (messages, chunks, kept_until, stopped_because) = match result {
        Ok(r) => r,
        Err(e) => {
            // Nothing half-written stays behind; the input is untouched.
            let _ = std::fs::remove_file(&tmp);
            return Err(e);
        }
    };
    std::fs::rename(&tmp, out).map_err(io_error(&tmp, "renaming to the recovered name"))?;
    let bytes_dropped = if stopped_because.is_some() {
        data.len() as u64 - kept_until
    } else {
        0
    };
    Ok(RecoverReport {
        out: out.to_path_buf(),
        messages,
        chunks,
        bytes_dropped,
        stopped_because,
    })
}

/// Where [`recover`] writes before renaming to `out`: `<out>.recovering.partial`, never the
/// input itself. (`partial_path(out)` would be the input in the usual call, recovering
/// `run.mcap.partial` to `run.mcap`; writing there would destroy the only copy of the run if the
/// recovery failed half-way, e.g. on a full disk.)
fn temp_path(partial: &Path, out: &Path) -> PathBuf {
    let mut s = out.as_os_str().to_owned();
    s.push(".recovering");
    let mut tmp = partial_path(Path::new(&s));
    let same = |a: &Path, b: &Path| {
        a == b || matches!((a.canonicalize(), b.canonicalize()), (Ok(x), Ok(y)) if x == y)
    };
    while same(&tmp, partial) {
        let mut s = tmp.into_os_string();
        s.push(".partial");
        tmp = PathBuf::from(s);
    }
    tmp
}

/// Reads the data section from `c` (just past the header) into a recording at `tmp`: messages
/// kept, chunks kept, the input's offset after the last record kept, and why reading stopped
/// early (if it did).
fn recover_into(
    mut c: Cursor<'_>,
    partial: &Path,
    tmp: &Path,
    defaults: WriterOptions,
) -> Result<(u64, u64, u64, Option<String>), RecordingError> {
    let mcap = McapWriter::create(tmp, &defaults)?;
    let mut rec = Recoverer {
        mcap,
        schema_ids: HashMap::new(),
        chunks: 0,
    };
    let mut buf = Vec::new();
    let mut kept_until = c.offset();
    let mut stopped_because = None;
    loop {
        if c.is_empty() {
            stopped_because = Some(format!(
                "the file ends at byte {} without a data end record",
                c.offset()
            ));
            break;
        }
        let r = match c.record() {
            Ok(r) => r,
            Err(e) => {
                stopped_because = Some(e.in_file(partial).to_string());
                break;
            }
        };
        let step = match r.opcode {
            op::SCHEMA => rec.schema(&r)?,
            op::CHANNEL => rec.channel(&r)?,
            op::MESSAGE => rec.message(&r).map(Ok)?,
            op::CHUNK => rec.chunk(&r, &mut buf)?,
            op::METADATA => match parse_metadata(&r) {
                Ok(m) => rec.mcap.write_metadata(&m.name, &m.metadata).map(Ok)?,
                Err(e) => Err(e),
            },
            op::ATTACHMENT => match parse_attachment(&r) {
                Ok(a) => rec
                    .mcap
                    .attach(a.name, a.media_type, a.log_time, a.create_time, a.data)
                    .map(Ok)?,
                Err(e) => Err(e),
            },
            op::DATA_END | op::FOOTER => {
                kept_until = r.end();
                break;
            }
            _ => Ok(()),
        };
        if let Err(e) = step {
            stopped_because = Some(e.in_file(partial).to_string());
            break;
        }
        kept_until = r.end();
    }
    let messages = rec.mcap.message_count();
    let chunks = rec.chunks;
    rec.mcap.finish()?;
    Ok((messages, chunks, kept_until, stopped_because))
}
