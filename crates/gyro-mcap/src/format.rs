//! MCAP records on the byte level (spec: mcap.dev/spec): opcodes, little-endian encoders for the
//! writer, and a bounds-checked cursor plus record parsers for the reader. Every length read from a
//! file is checked against the bytes that remain before anything is sliced or allocated.

use std::collections::BTreeMap;

use crate::error::ParseError;

pub(crate) const MAGIC: &[u8; 8] = b"\x89MCAP0\r\n";

pub(crate) mod op {
    pub const HEADER: u8 = 0x01;
    pub const FOOTER: u8 = 0x02;
    pub const SCHEMA: u8 = 0x03;
    pub const CHANNEL: u8 = 0x04;
    pub const MESSAGE: u8 = 0x05;
    pub const CHUNK: u8 = 0x06;
    pub const MESSAGE_INDEX: u8 = 0x07;
    pub const CHUNK_INDEX: u8 = 0x08;
    pub const ATTACHMENT: u8 = 0x09;
    pub const ATTACHMENT_INDEX: u8 = 0x0A;
    pub const STATISTICS: u8 = 0x0B;
    pub const METADATA: u8 = 0x0C;
    pub const METADATA_INDEX: u8 = 0x0D;
    pub const SUMMARY_OFFSET: u8 = 0x0E;
    pub const DATA_END: u8 = 0x0F;
}

/// Footer record length on disk: opcode, length, summary_start, summary_offset_start, crc.
pub(crate) const FOOTER_RECORD_LEN: usize = 1 + 8 + 8 + 8 + 4;

/// A human name for an opcode, for error messages.
pub(crate) fn op_name(opcode: u8) -> &'static str {
    match opcode {
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
        _ => "unknown record",
    }
}

// ---------------------------------------------------------------------------------------------
// Encoding

pub(crate) fn put_u16(buf: &mut Vec<u8>, v: u16) {
    buf.extend_from_slice(&v.to_le_bytes());
}
pub(crate) fn put_u32(buf: &mut Vec<u8>, v: u32) {
    buf.extend_from_slice(&v.to_le_bytes());
}
pub(crate) fn put_u64(buf: &mut Vec<u8>, v: u64) {
    buf.extend_from_slice(&v.to_le_bytes());
}
/// Strings and small byte arrays carry a u32 length. Callers keep them below 4 GiB (names,
/// schemas); `len32` saturates, and the writer validates sizes before it gets here.
pub(crate) fn put_str(buf: &mut Vec<u8>, s: &str) {
    put_bytes32(buf, s.as_bytes());
}
pub(crate) fn put_bytes32(buf: &mut Vec<u8>, b: &[u8]) {
    put_u32(buf, len32(b.len()));
    buf.extend_from_slice(b);
}
pub(crate) fn len32(n: usize) -> u32 {
    u32::try_from(n).unwrap_or(u32::MAX)
}
pub(crate) fn put_str_map(buf: &mut Vec<u8>, map: &BTreeMap<String, String>) {
    let start = buf.len();
    put_u32(buf, 0);
    for (k, v) in map {
        put_str(buf, k);
        put_str(buf, v);
    }
    let len = buf.len() - start - 4;
    patch_u32(buf, start, len);
}
pub(crate) fn patch_u32(buf: &mut [u8], at: usize, v: usize) {
    buf[at..at + 4].copy_from_slice(&len32(v).to_le_bytes());
}
/// Starts a record: opcode and a placeholder length. Returns where the length sits.
pub(crate) fn begin_record(buf: &mut Vec<u8>, opcode: u8) -> usize {
    buf.push(opcode);
    let at = buf.len();
    put_u64(buf, 0);
    at
}
pub(crate) fn end_record(buf: &mut [u8], len_at: usize) {
    let len = (buf.len() - len_at - 8) as u64;
    buf[len_at..len_at + 8].copy_from_slice(&len.to_le_bytes());
}

// ---------------------------------------------------------------------------------------------
// Parsing

/// A bounds-checked reader over `data`, whose first byte sits at file offset `base`.
#[derive(Clone)]
pub(crate) struct Cursor<'a> {
    data: &'a [u8],
    pos: usize,
    base: u64,
    record: &'static str,
}

impl<'a> Cursor<'a> {
    pub(crate) fn new(data: &'a [u8], base: u64, record: &'static str) -> Self {
        Self {
            data,
            pos: 0,
            base,
            record,
        }
    }
    pub(crate) fn offset(&self) -> u64 {
        self.base + self.pos as u64
    }
    pub(crate) fn remaining(&self) -> usize {
        self.data.len() - self.pos
    }
    pub(crate) fn is_empty(&self) -> bool {
        self.remaining() == 0
    }
    pub(crate) fn fail(&self, expected: impl Into<String>) -> ParseError {
        ParseError::new(self.offset(), self.record, expected)
    }
    pub(crate) fn take(&mut self, n: usize, what: &str) -> Result<&'a [u8], ParseError> {
        if n > self.remaining() {
            return Err(self.fail(format!(
                "{what} of {n} bytes, but only {} remain",
                self.remaining()
            )));
        }
        let s = &self.data[self.pos..self.pos + n];
        self.pos += n;
        Ok(s)
    }
    fn array<const N: usize>(&mut self, what: &str) -> Result<[u8; N], ParseError> {
        let s = self.take(N, what)?;
        let mut a = [0u8; N];
        a.copy_from_slice(s);
        Ok(a)
    }
    pub(crate) fn u8(&mut self, what: &str) -> Result<u8, ParseError> {
        Ok(self.array::<1>(what)?[0])
    }
    pub(crate) fn u16(&mut self, what: &str) -> Result<u16, ParseError> {
        Ok(u16::from_le_bytes(self.array(what)?))
    }
    pub(crate) fn u32(&mut self, what: &str) -> Result<u32, ParseError> {
        Ok(u32::from_le_bytes(self.array(what)?))
    }
    pub(crate) fn u64(&mut self, what: &str) -> Result<u64, ParseError> {
        Ok(u64::from_le_bytes(self.array(what)?))
    }
    /// A length field that must fit in what remains.
    fn len_u64(&mut self, what: &str) -> Result<usize, ParseError> {
        let at = self.offset();
        let n = self.u64(what)?;
        usize::try_from(n)
            .ok()
            .filter(|&n| n <= self.remaining())
            .ok_or_else(|| {
                ParseError::new(
                    at,
                    self.record,
                    format!(
                        "{what} length at most {} (the bytes left), found {n}",
                        self.remaining()
                    ),
                )
            })
    }
    fn len_u32(&mut self, what: &str) -> Result<usize, ParseError> {
        let at = self.offset();
        let n = self.u32(what)? as usize;
        if n > self.remaining() {
            return Err(ParseError::new(
                at,
                self.record,
                format!(
                    "{what} length at most {} (the bytes left), found {n}",
                    self.remaining()
                ),
            ));
        }
        Ok(n)
    }
    pub(crate) fn bytes32(&mut self, what: &str) -> Result<&'a [u8], ParseError> {
        let n = self.len_u32(what)?;
        self.take(n, what)
    }
    pub(crate) fn bytes64(&mut self, what: &str) -> Result<&'a [u8], ParseError> {
        let n = self.len_u64(what)?;
        self.take(n, what)
    }
    pub(crate) fn str(&mut self, what: &str) -> Result<&'a str, ParseError> {
        let at = self.offset();
        let b = self.bytes32(what)?;
        std::str::from_utf8(b)
            .map_err(|_| ParseError::new(at, self.record, format!("{what} as UTF-8 text")))
    }
    pub(crate) fn str_map(&mut self, what: &str) -> Result<BTreeMap<String, String>, ParseError> {
        let n = self.len_u32(what)?;
        let base = self.offset();
        let mut inner = Cursor::new(self.take(n, what)?, base, self.record);
        let mut map = BTreeMap::new();
        while !inner.is_empty() {
            let k = inner.str("map key")?;
            let v = inner.str("map value")?;
            map.insert(k.to_owned(), v.to_owned());
        }
        Ok(map)
    }
    /// A Map<u16, u64> (chunk index message-index offsets, statistics channel counts).
    pub(crate) fn u16_u64_map(&mut self, what: &str) -> Result<Vec<(u16, u64)>, ParseError> {
        let n = self.len_u32(what)?;
        if n % 10 != 0 {
            return Err(self.fail(format!("{what} byte length a multiple of 10, found {n}")));
        }
        let base = self.offset();
        let mut inner = Cursor::new(self.take(n, what)?, base, self.record);
        let mut out = Vec::with_capacity(n / 10);
        while !inner.is_empty() {
            out.push((inner.u16("channel id")?, inner.u64("value")?));
        }
        Ok(out)
    }

    /// The next record: opcode, body (bounds-checked) and the body's file offset.
    pub(crate) fn record(&mut self) -> Result<RawRecord<'a>, ParseError> {
        let offset = self.offset();
        let opcode = self.u8("record opcode")?;
        let n = self.len_u64("record")?;
        let body_offset = self.offset();
        let body = self.take(n, "record body")?;
        Ok(RawRecord {
            opcode,
            offset,
            body,
            body_offset,
        })
    }
}

pub(crate) struct RawRecord<'a> {
    pub opcode: u8,
    /// File offset of the opcode byte.
    pub offset: u64,
    pub body: &'a [u8],
    pub body_offset: u64,
}

impl<'a> RawRecord<'a> {
    pub(crate) fn cursor(&self) -> Cursor<'a> {
        Cursor::new(self.body, self.body_offset, op_name(self.opcode))
    }
    pub(crate) fn end(&self) -> u64 {
        self.body_offset + self.body.len() as u64
    }
}

#[derive(Debug, Clone, PartialEq)]
pub(crate) struct SchemaRecord {
    pub id: u16,
    pub name: String,
    pub encoding: String,
    pub data: Vec<u8>,
}

pub(crate) fn parse_schema(r: &RawRecord) -> Result<SchemaRecord, ParseError> {
    let mut c = r.cursor();
    Ok(SchemaRecord {
        id: c.u16("schema id")?,
        name: c.str("schema name")?.to_owned(),
        encoding: c.str("schema encoding")?.to_owned(),
        data: c.bytes32("schema data")?.to_vec(),
    })
}

#[derive(Debug, Clone, PartialEq)]
pub(crate) struct ChannelRecord {
    pub id: u16,
    pub schema_id: u16,
    pub topic: String,
    pub message_encoding: String,
    pub metadata: BTreeMap<String, String>,
}

pub(crate) fn parse_channel(r: &RawRecord) -> Result<ChannelRecord, ParseError> {
    let mut c = r.cursor();
    Ok(ChannelRecord {
        id: c.u16("channel id")?,
        schema_id: c.u16("schema id")?,
        topic: c.str("topic")?.to_owned(),
        message_encoding: c.str("message encoding")?.to_owned(),
        metadata: c.str_map("channel metadata")?,
    })
}

pub(crate) struct MessageRecord<'a> {
    pub channel_id: u16,
    pub sequence: u32,
    pub log_time: u64,
    pub publish_time: u64,
    pub data: &'a [u8],
}

pub(crate) fn parse_message<'a>(r: &RawRecord<'a>) -> Result<MessageRecord<'a>, ParseError> {
    let mut c = r.cursor();
    let channel_id = c.u16("channel id")?;
    let sequence = c.u32("sequence")?;
    let log_time = c.u64("log time")?;
    let publish_time = c.u64("publish time")?;
    let data = c.take(c.remaining(), "message data")?;
    Ok(MessageRecord {
        channel_id,
        sequence,
        log_time,
        publish_time,
        data,
    })
}

pub(crate) struct ChunkRecord<'a> {
    pub uncompressed_size: u64,
    pub uncompressed_crc: u32,
    pub compression: &'a str,
    pub records: &'a [u8],
}

pub(crate) fn parse_chunk<'a>(r: &RawRecord<'a>) -> Result<ChunkRecord<'a>, ParseError> {
    let mut c = r.cursor();
    let _message_start_time = c.u64("message start time")?;
    let _message_end_time = c.u64("message end time")?;
    Ok(ChunkRecord {
        uncompressed_size: c.u64("uncompressed size")?,
        uncompressed_crc: c.u32("uncompressed crc")?,
        compression: c.str("compression")?,
        records: c.bytes64("chunk records")?,
    })
}

pub(crate) struct MessageIndexRecord<'a> {
    pub channel_id: u16,
    /// (log_time, offset) pairs, 16 bytes each.
    pub entries: &'a [u8],
}

impl MessageIndexRecord<'_> {
    pub(crate) fn iter(&self) -> impl Iterator<Item = (u64, u64)> + '_ {
        self.entries.chunks_exact(16).map(|e| {
            let mut t = [0u8; 8];
            let mut o = [0u8; 8];
            t.copy_from_slice(&e[..8]);
            o.copy_from_slice(&e[8..]);
            (u64::from_le_bytes(t), u64::from_le_bytes(o))
        })
    }
}

pub(crate) fn parse_message_index<'a>(
    r: &RawRecord<'a>,
) -> Result<MessageIndexRecord<'a>, ParseError> {
    let mut c = r.cursor();
    let channel_id = c.u16("channel id")?;
    let entries = c.bytes32("message index entries")?;
    if entries.len() % 16 != 0 {
        return Err(c.fail("message index entries of 16 bytes each"));
    }
    Ok(MessageIndexRecord {
        channel_id,
        entries,
    })
}

#[derive(Debug, Clone)]
pub(crate) struct ChunkIndexRecord {
    pub chunk_start_offset: u64,
    pub chunk_length: u64,
    pub message_index_offsets: Vec<(u16, u64)>,
}

pub(crate) fn parse_chunk_index(r: &RawRecord) -> Result<ChunkIndexRecord, ParseError> {
    let mut c = r.cursor();
    let _message_start_time = c.u64("message start time")?;
    let _message_end_time = c.u64("message end time")?;
    let chunk_start_offset = c.u64("chunk start offset")?;
    let chunk_length = c.u64("chunk length")?;
    let message_index_offsets = c.u16_u64_map("message index offsets")?;
    let _message_index_length = c.u64("message index length")?;
    let _compression = c.str("compression")?;
    let _compressed_size = c.u64("compressed size")?;
    let _uncompressed_size = c.u64("uncompressed size")?;
    Ok(ChunkIndexRecord {
        chunk_start_offset,
        chunk_length,
        message_index_offsets,
    })
}

pub(crate) struct AttachmentRecord<'a> {
    pub log_time: u64,
    pub create_time: u64,
    pub name: &'a str,
    pub media_type: &'a str,
    pub data: &'a [u8],
}

pub(crate) fn parse_attachment<'a>(r: &RawRecord<'a>) -> Result<AttachmentRecord<'a>, ParseError> {
    let mut c = r.cursor();
    let log_time = c.u64("log time")?;
    let create_time = c.u64("create time")?;
    let name = c.str("attachment name")?;
    let media_type = c.str("media type")?;
    let data = c.bytes64("attachment data")?;
    let covered = r.body.len() - c.remaining();
    let crc_at = c.offset();
    let crc = c.u32("attachment crc")?;
    if crc != 0 {
        let actual = crc32fast::hash(&r.body[..covered]);
        if actual != crc {
            return Err(ParseError::new(
                crc_at,
                "attachment",
                format!("attachment CRC {crc:#010x}, computed {actual:#010x}"),
            ));
        }
    }
    Ok(AttachmentRecord {
        log_time,
        create_time,
        name,
        media_type,
        data,
    })
}

#[derive(Debug, Clone)]
pub(crate) struct AttachmentIndexRecord {
    pub offset: u64,
    pub length: u64,
}

pub(crate) fn parse_attachment_index(r: &RawRecord) -> Result<AttachmentIndexRecord, ParseError> {
    let mut c = r.cursor();
    Ok(AttachmentIndexRecord {
        offset: c.u64("attachment offset")?,
        length: c.u64("attachment length")?,
    })
}

pub(crate) struct MetadataRecord {
    pub name: String,
    pub metadata: BTreeMap<String, String>,
}

pub(crate) fn parse_metadata(r: &RawRecord) -> Result<MetadataRecord, ParseError> {
    let mut c = r.cursor();
    Ok(MetadataRecord {
        name: c.str("metadata name")?.to_owned(),
        metadata: c.str_map("metadata entries")?,
    })
}

#[derive(Debug, Clone)]
pub(crate) struct MetadataIndexRecord {
    pub offset: u64,
    pub length: u64,
}

pub(crate) fn parse_metadata_index(r: &RawRecord) -> Result<MetadataIndexRecord, ParseError> {
    let mut c = r.cursor();
    Ok(MetadataIndexRecord {
        offset: c.u64("metadata offset")?,
        length: c.u64("metadata length")?,
    })
}

#[derive(Debug, Clone, Default)]
pub(crate) struct StatisticsRecord {
    pub message_count: u64,
}

pub(crate) fn parse_statistics(r: &RawRecord) -> Result<StatisticsRecord, ParseError> {
    let mut c = r.cursor();
    let message_count = c.u64("message count")?;
    let _schema_count = c.u16("schema count")?;
    let _channel_count = c.u32("channel count")?;
    let _attachment_count = c.u32("attachment count")?;
    let _metadata_count = c.u32("metadata count")?;
    let _chunk_count = c.u32("chunk count")?;
    let _start = c.u64("message start time")?;
    let _end = c.u64("message end time")?;
    let _channel_message_counts = c.u16_u64_map("channel message counts")?;
    Ok(StatisticsRecord { message_count })
}

pub(crate) struct Footer {
    pub summary_start: u64,
    pub summary_offset_start: u64,
    pub summary_crc: u32,
}

pub(crate) fn parse_footer(r: &RawRecord) -> Result<Footer, ParseError> {
    let mut c = r.cursor();
    Ok(Footer {
        summary_start: c.u64("summary start")?,
        summary_offset_start: c.u64("summary offset start")?,
        summary_crc: c.u32("summary crc")?,
    })
}

thread_local! {
    /// One zstd decompression context per thread, reused across chunks (a context is ~100 KiB).
    static DECOMPRESSOR: std::cell::RefCell<Option<zstd::bulk::Decompressor<'static>>> =
        const { std::cell::RefCell::new(None) };
}

/// Decompresses a chunk's records. Allocation grows with the bytes actually produced and stops at
/// the declared size (so a lying length field cannot make us reserve gigabytes), which is itself
/// capped at [`MAX_CHUNK_UNCOMPRESSED`].
pub(crate) fn decompress_chunk(
    chunk: &ChunkRecord,
    chunk_offset: u64,
    out: &mut Vec<u8>,
) -> Result<(), ParseError> {
    use std::io::Read;
    out.clear();
    let declared = chunk.uncompressed_size;
    if declared > MAX_CHUNK_UNCOMPRESSED {
        return Err(ParseError::new(
            chunk_offset,
            "chunk",
            format!(
                "an uncompressed size of at most {MAX_CHUNK_UNCOMPRESSED} bytes, found {declared}"
            ),
        ));
    }
    match chunk.compression {
        "" => out.extend_from_slice(chunk.records),
        "zstd" => {
            let compressed = chunk.records.len() as u64;
            if declared
                <= compressed
                    .saturating_mul(PLAUSIBLE_ZSTD_RATIO)
                    .saturating_add(1 << 20)
            {
                // The common case: one pass into a buffer of the declared size (reused across
                // chunks by the callers). The bound keeps a lying size from reserving much more
                // than the compressed bytes could plausibly produce.
                out.reserve(declared as usize);
                DECOMPRESSOR
                    .with(|cell| {
                        let mut slot = cell.borrow_mut();
                        if slot.is_none() {
                            *slot = Some(zstd::bulk::Decompressor::new()?);
                        }
                        match slot.as_mut() {
                            Some(d) => d.decompress_to_buffer(chunk.records, out),
                            None => Ok(0),
                        }
                    })
                    .map_err(|e| {
                        ParseError::new(
                            chunk_offset,
                            "chunk",
                            format!("valid zstd data of the declared size ({e})"),
                        )
                    })?;
            } else {
                // Implausible ratio: let the buffer grow only with the bytes zstd produces.
                out.reserve((compressed.saturating_mul(16) + 4096).min(declared) as usize);
                let decoder =
                    zstd::stream::read::Decoder::with_buffer(chunk.records).map_err(|e| {
                        ParseError::new(chunk_offset, "chunk", format!("a zstd stream ({e})"))
                    })?;
                decoder
                    .take(declared.saturating_add(1))
                    .read_to_end(out)
                    .map_err(|e| {
                        ParseError::new(chunk_offset, "chunk", format!("valid zstd data ({e})"))
                    })?;
            }
        }
        other => {
            return Err(ParseError::new(
                chunk_offset,
                "chunk",
                format!("compression \"zstd\" or none, found {other:?} (not supported here)"),
            ));
        }
    }
    if out.len() as u64 != declared {
        return Err(ParseError::new(
            chunk_offset,
            "chunk",
            format!(
                "{declared} bytes after decompression (the declared size), found {}{}",
                if out.len() as u64 > declared {
                    "more than "
                } else {
                    ""
                },
                out.len().min(declared as usize)
            ),
        ));
    }
    if chunk.uncompressed_crc != 0 {
        let actual = crc32fast::hash(out);
        if actual != chunk.uncompressed_crc {
            return Err(ParseError::new(
                chunk_offset,
                "chunk",
                format!(
                    "uncompressed CRC {:#010x}, computed {actual:#010x}",
                    chunk.uncompressed_crc
                ),
            ));
        }
    }
    Ok(())
}

/// Uncompressed/compressed ratio up to which a chunk's buffer is reserved at its declared size.
const PLAUSIBLE_ZSTD_RATIO: u64 = 64;

/// Chunks larger than this are refused (our writer makes ~1 MiB chunks; other writers a few MiB).
pub(crate) const MAX_CHUNK_UNCOMPRESSED: u64 = 256 << 20;
