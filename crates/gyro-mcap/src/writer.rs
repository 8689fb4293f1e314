//! Writing recordings: [`RecordingWriter`] (typed channels, the public API) over [`McapWriter`] (MCAP
//! records, chunking, indexes and the summary; also used by `recover` to re-emit raw messages).
//!
//! Why not the `mcap` crate's writer: on the same 1 512 000 messages (6 h of the throughput
//! load, files checked to hold the same message bytes), in one run (2026-12-02, 2 cores shared
//! with a build), it used 1.5× the CPU time of this writer at the same zstd level 3 (1.01
//! against 0.66 CPU s; wall 1.13 against 0.66 s) and 3.3× that of this writer's default level
//! −4, which it cannot use (it takes no negative level; at its level 1, 0.79 CPU s for a 5 %
//! larger file, against 0.31). Outside 1.5× at the levels each runs by default, so this writer
//! stays. `cargo bench -p gyro-mcap --bench vs_mcap`.

use std::collections::{BTreeMap, HashMap};
use std::fs::File;
use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, mpsc};
use std::thread::JoinHandle;
use std::time::Instant;

use crate::error::{RecordingError, io_error};
use crate::format::{
    MAGIC, begin_record, end_record, len32, op, patch_u32, put_bytes32, put_str, put_str_map,
    put_u16, put_u32, put_u64,
};
use crate::schema::{
    FRAME_TRANSFORM_FDS, FieldKind, POSE_SCHEMA_NAME, Pose, RecordSchema, Tag, Value, WIRE_FIXED64,
    WIRE_LEN, WIRE_VARINT, encode_pose, pose_encoded_len, put_varint, varint_len,
};

/// How the writer cuts and compresses chunks. Plain data; `Default` gives the values below.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct WriterOptions {
    /// Uncompressed bytes of records after which a chunk is closed. Default 1 MiB.
    pub chunk_size_bytes: u64,
    /// zstd level of chunk compression. Default -4 (zstd's fast strategy with acceleration 4):
    /// compression is most of the writer's CPU. On 24-h 10-Hz recordings of harbour-50n and
    /// turn-90 (`examples/zstd_levels.rs`), level -4 compresses 1.25× and 1.19× faster than -1
    /// for chunks 14 % and 8 % larger, files 8 % and 5 % larger (message indexes are stored
    /// uncompressed); level 1 is 1.2× slower than -1 for about the same size, and -3 is both
    /// slower and larger than -4 on these.
    pub zstd_level: i32,
    /// Wall-clock seconds after which an open chunk is closed and handed to the operating system,
    /// however small, so a killed process loses at most this much. Default 1.0.
    pub flush_interval_s: f64,
    /// Bytes written between two writebacks to disk started while the file grows (on a thread
    /// of their own, never waited for), so the sync at `finish` has little left. Default 32 MiB;
    /// 0 leaves it all to `finish`.
    pub sync_every_bytes: u64,
}

impl Default for WriterOptions {
    fn default() -> Self {
        Self {
            chunk_size_bytes: 1 << 20,
            zstd_level: -4,
            flush_interval_s: 1.0,
            sync_every_bytes: 32 << 20,
        }
    }
}

/// What [`RecordingWriter::finish`] wrote.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct WriteSummary {
    /// The final path (the `.partial` file was renamed to it).
    pub path: PathBuf,
    /// File size in bytes.
    pub bytes: u64,
    /// Messages on all channels.
    pub messages: u64,
}

/// A channel handle returned by the `add_*_channel` calls of one writer.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct ChannelId(u32);

/// The file, its position and the running CRC of the section being written.
struct Out {
    path: PathBuf,
    file: BufWriter<File>,
    pos: u64,
    crc: crc32fast::Hasher,
}

impl Out {
    fn emit(&mut self, bytes: &[u8]) -> Result<(), RecordingError> {
        self.crc.update(bytes);
        self.pos += bytes.len() as u64;
        self.file
            .write_all(bytes)
            .map_err(io_error(&self.path, "writing"))
    }
}

struct McapChannel {
    id: u16,
    topic: String,
    sequence: u32,
    message_count: u64,
    /// (log_time, offset in the chunk's records) of this chunk's messages, as the message index
    /// record stores them (16 little-endian bytes each).
    chunk_index: Vec<u8>,
}

/// A closed chunk on its way to the file: its records, time range and message indexes, and
/// (after the compressing stage) its compressed bytes and CRC.
#[derive(Default)]
struct ChunkJob {
    records: Vec<u8>,
    start_time: u64,
    end_time: u64,
    /// The encoded message index records, one per channel with messages in the chunk.
    indexes: Vec<u8>,
    /// (channel id, offset of its message index record within `indexes`).
    index_offsets: Vec<(u16, u64)>,
    compressed: Vec<u8>,
    uncompressed_crc: u32,
}

/// Work for the file side, done in the order it was sent.
enum Job {
    /// Records to append as they are (header, schemas, channels).
    Bytes(Vec<u8>),
    Metadata {
        record: Vec<u8>,
        name: String,
    },
    Attachment {
        record: Vec<u8>,
        log_time: u64,
        create_time: u64,
        data_len: u64,
        name: String,
        media_type: String,
    },
    Chunk(ChunkJob),
    /// Compressing a chunk failed.
    Failed(RecordingError),
    /// Reply (true = every job so far succeeded) once everything before it is written and
    /// handed to the operating system.
    Sync(mpsc::SyncSender<bool>),
}

/// A chunk compressor at `level`. At zstd's fast levels (1 and below) its match-finder table
/// shrinks from 2¹³ to 2¹² entries (16 KiB, so it stays in L1 cache): on 24-h recordings'
/// chunks that compresses 3–6 % faster for 0.3–0.4 % more bytes (`examples/zstd_levels.rs`
/// with `-4:hl=12`). Slower levels keep their own tables.
fn compressor(level: i32) -> std::io::Result<zstd::bulk::Compressor<'static>> {
    let mut c = zstd::bulk::Compressor::new(level)?;
    if level <= 1 {
        c.set_parameter(zstd::zstd_safe::CParameter::HashLog(12))?;
    }
    Ok(c)
}

/// Compresses a chunk in place (`compressed`, `uncompressed_crc`).
fn compress(
    compressor: &mut zstd::bulk::Compressor<'static>,
    c: &mut ChunkJob,
    path: &Path,
) -> Result<(), RecordingError> {
    c.uncompressed_crc = crc32fast::hash(&c.records);
    c.compressed.clear();
    c.compressed
        .reserve(zstd::zstd_safe::compress_bound(c.records.len()));
    compressor
        .compress_to_buffer(&c.records, &mut c.compressed)
        .map(drop)
        .map_err(io_error(path, "compressing a chunk"))
}

/// The file side of an [`McapWriter`]: the file, and everything whose value depends on positions in it
/// (chunk, attachment and metadata indexes). Runs on a writer thread fed by compressing threads
/// (see [`spawn_workers`]); the summary is written after it is joined.
struct FileSide {
    out: Out,
    chunk_index_records: Vec<u8>,
    attachment_index_records: Vec<u8>,
    metadata_index_records: Vec<u8>,
    chunk_count: u32,
    attachment_count: u32,
    metadata_count: u32,
    /// Writeback while the file grows (on the writer thread's side; none when inline).
    syncer: Option<Syncer>,
}

/// Writeback while the file grows: after every `sync_every_bytes` the writer thread asks a
/// syncing thread to `sync_data` a clone of the file handle, and never waits for it, so the
/// durable sync in [`McapWriter::finish`] finds little left to write. (Without it that sync waited for
/// the whole file: 0.2 s of the 0.7-s write of the 389-MB throughput bench.)
struct Syncer {
    ask: mpsc::SyncSender<()>,
    thread: JoinHandle<std::io::Result<()>>,
    unsynced: u64,
    every: u64,
}

impl Syncer {
    fn start(file: &File, every: u64) -> Option<Syncer> {
        if every == 0 {
            return None;
        }
        let clone = file.try_clone().ok()?;
        let (ask, asked) = mpsc::sync_channel::<()>(1);
        let thread = std::thread::Builder::new()
            .name("gyro-mcap-sync".into())
            .spawn(move || {
                for () in asked {
                    clone.sync_data()?;
                }
                Ok(())
            })
            .ok()?;
        Some(Syncer {
            ask,
            thread,
            unsynced: 0,
            every,
        })
    }

    fn wrote(&mut self, bytes: u64) {
        self.unsynced += bytes;
        if self.unsynced >= self.every {
            // A request already queued covers these bytes when it runs: never wait.
            let _ = self.ask.try_send(());
            self.unsynced = 0;
        }
    }

    /// Waits for the last writeback. Its error is reported here: the file handles share one
    /// open file, so the final sync would not see an error this one has taken.
    fn stop(self) -> std::io::Result<()> {
        drop(self.ask);
        self.thread
            .join()
            .unwrap_or_else(|_| Err(std::io::Error::other("the syncing thread panicked")))
    }
}

impl FileSide {
    fn apply(&mut self, job: &mut Job) -> Result<(), RecordingError> {
        match job {
            Job::Bytes(b) => self.out.emit(b),
            Job::Metadata { record, name } => {
                let offset = self.out.pos;
                self.out.emit(record)?;
                let ix = &mut self.metadata_index_records;
                let at = begin_record(ix, op::METADATA_INDEX);
                put_u64(ix, offset);
                put_u64(ix, record.len() as u64);
                put_str(ix, name);
                end_record(ix, at);
                self.metadata_count += 1;
                Ok(())
            }
            Job::Attachment {
                record,
                log_time,
                create_time,
                data_len,
                name,
                media_type,
            } => {
                let offset = self.out.pos;
                self.out.emit(record)?;
                let ix = &mut self.attachment_index_records;
                let at = begin_record(ix, op::ATTACHMENT_INDEX);
                put_u64(ix, offset);
                put_u64(ix, record.len() as u64);
                put_u64(ix, *log_time);
                put_u64(ix, *create_time);
                put_u64(ix, *data_len);
                put_str(ix, name);
                put_str(ix, media_type);
                end_record(ix, at);
                self.attachment_count += 1;
                Ok(())
            }
            Job::Chunk(c) => self.write_chunk(c),
            Job::Failed(e) => Err(std::mem::replace(
                e,
                RecordingError::Usage {
                    path: self.out.path.clone(),
                    call: "compressing".into(),
                    expected: "an error reported once".into(),
                },
            )),
            Job::Sync(_) => self
                .out
                .file
                .flush()
                .map_err(io_error(&self.out.path, "flushing")),
        }
    }

    /// Writes a compressed chunk with its message indexes, then hands the bytes to the
    /// operating system (so they survive the process being killed).
    fn write_chunk(&mut self, c: &ChunkJob) -> Result<(), RecordingError> {
        let chunk_start = self.out.pos;
        let mut head = Vec::with_capacity(64);
        head.push(op::CHUNK);
        let body_len = 8 + 8 + 8 + 4 + (4 + 4) + 8 + c.compressed.len();
        put_u64(&mut head, body_len as u64);
        put_u64(&mut head, c.start_time);
        put_u64(&mut head, c.end_time);
        put_u64(&mut head, c.records.len() as u64);
        put_u32(&mut head, c.uncompressed_crc);
        put_str(&mut head, "zstd");
        put_u64(&mut head, c.compressed.len() as u64);
        self.out.emit(&head)?;
        self.out.emit(&c.compressed)?;
        let chunk_length = self.out.pos - chunk_start;
        let index_start = self.out.pos;
        self.out.emit(&c.indexes)?;

        let b = &mut self.chunk_index_records;
        let at = begin_record(b, op::CHUNK_INDEX);
        put_u64(b, c.start_time);
        put_u64(b, c.end_time);
        put_u64(b, chunk_start);
        put_u64(b, chunk_length);
        put_u32(b, len32(c.index_offsets.len() * 10));
        for &(id, o) in &c.index_offsets {
            put_u16(b, id);
            put_u64(b, index_start + o);
        }
        put_u64(b, c.indexes.len() as u64);
        put_str(b, "zstd");
        put_u64(b, c.compressed.len() as u64);
        put_u64(b, c.records.len() as u64);
        end_record(b, at);
        self.chunk_count += 1;
        self.out
            .file
            .flush()
            .map_err(io_error(&self.out.path, "flushing a chunk"))?;
        if let Some(s) = &mut self.syncer {
            s.wrote(self.out.pos - chunk_start);
        }
        Ok(())
    }
}

/// Where the file side runs: on worker threads (the usual case), inline (when no thread could
/// be started), or nowhere (after it failed or was joined).
enum FileHandle {
    Inline {
        side: Box<FileSide>,
        compressor: zstd::bulk::Compressor<'static>,
    },
    Workers(Workers),
    Gone,
}

/// The threads of an [`McapWriter`]: job `n` goes to compressing thread `n % k`, which compresses chunks
/// and passes everything on; the writer thread takes job `n` from thread `n % k`, so the file is
/// written in submission order while `k` chunks compress at once.
struct Workers {
    inputs: Vec<mpsc::SyncSender<Job>>,
    next: usize,
    /// Chunk buffers the writer is done with, for reuse.
    recycled: mpsc::Receiver<ChunkJob>,
    failed: Arc<AtomicBool>,
    compressors: Vec<JoinHandle<()>>,
    writer: JoinHandle<(Box<FileSide>, Option<RecordingError>)>,
}

/// Jobs queued per compressing thread beyond the one it works on: enough to ride out a slow
/// write, few enough that a killed process loses only milliseconds more than the open chunk.
const QUEUED_PER_THREAD: usize = 1;

/// How many chunks compress at once: one per core, at most four.
fn compressing_threads() -> usize {
    std::thread::available_parallelism().map_or(1, |n| n.get().clamp(1, 4))
}

fn spawn_workers(
    mut side: Box<FileSide>,
    opts: &WriterOptions,
    path: &Path,
) -> Result<Workers, Box<FileSide>> {
    let zstd_level = opts.zstd_level;
    side.syncer = Syncer::start(side.out.file.get_ref(), opts.sync_every_bytes);
    let k = compressing_threads();
    let failed = Arc::new(AtomicBool::new(false));
    let mut inputs = Vec::with_capacity(k);
    let mut outputs = Vec::with_capacity(k);
    let mut compressors = Vec::with_capacity(k);
    for i in 0..k {
        let Ok(mut compressor) = compressor(zstd_level) else {
            return Err(side);
        };
        let (tx, rx) = mpsc::sync_channel::<Job>(QUEUED_PER_THREAD);
        let (out_tx, out_rx) = mpsc::sync_channel::<Job>(QUEUED_PER_THREAD);
        let path = path.to_path_buf();
        let spawned = std::thread::Builder::new()
            .name(format!("gyro-mcap-zstd-{i}"))
            .spawn(move || {
                for mut job in rx {
                    if let Job::Chunk(c) = &mut job
                        && let Err(e) = compress(&mut compressor, c, &path)
                    {
                        job = Job::Failed(e);
                    }
                    if out_tx.send(job).is_err() {
                        break;
                    }
                }
            });
        match spawned {
            Ok(h) => compressors.push(h),
            // Dropping the senders ends the threads already started.
            Err(_) => return Err(side),
        }
        inputs.push(tx);
        outputs.push(out_rx);
    }
    let (recycle, recycled) = mpsc::channel::<ChunkJob>();
    let flag = Arc::clone(&failed);
    // The side moves into the writer thread; if it cannot start, it comes back through here.
    let slot = Arc::new(std::sync::Mutex::new(Some(side)));
    let theirs = Arc::clone(&slot);
    let spawned = std::thread::Builder::new()
        .name("gyro-mcap-write".into())
        .spawn(move || {
            let mut side = theirs
                .lock()
                .ok()
                .and_then(|mut s| s.take())
                .expect("the file side is handed to the writer once");
            let mut error = None;
            for n in 0.. {
                // Job n is on output n % k; a closed output means no job n was sent.
                let Ok(mut job) = outputs[n % outputs.len()].recv() else {
                    break;
                };
                if error.is_none()
                    && let Err(e) = side.apply(&mut job)
                {
                    error = Some(e);
                    flag.store(true, Ordering::Release);
                }
                match job {
                    Job::Sync(reply) => {
                        let _ = reply.send(error.is_none());
                    }
                    Job::Chunk(mut c) => {
                        c.records.clear();
                        c.indexes.clear();
                        c.index_offsets.clear();
                        let _ = recycle.send(c);
                    }
                    _ => {}
                }
            }
            (side, error)
        });
    match spawned {
        Ok(writer) => Ok(Workers {
            inputs,
            next: 0,
            recycled,
            failed,
            compressors,
            writer,
        }),
        Err(_) => {
            drop(inputs);
            for h in compressors {
                let _ = h.join();
            }
            Err(slot
                .lock()
                .ok()
                .and_then(|mut s| s.take())
                .expect("the side is still here when the writer did not start"))
        }
    }
}

/// MCAP records to a file: chunks with message indexes, then DataEnd, summary and footer. The
/// caller's side (this struct) encodes messages into the open chunk and keeps per-channel
/// statistics; the file side compresses and writes, on a worker thread.
pub(crate) struct McapWriter {
    path: PathBuf,
    file: FileHandle,
    chunk_size: usize,
    chunk: Vec<u8>,
    chunk_start_time: u64,
    chunk_end_time: u64,
    touched: Vec<usize>,
    channels: Vec<McapChannel>,
    slot_of_id: HashMap<u16, usize>,
    /// Summary records, already encoded, by group.
    schema_records: Vec<u8>,
    channel_records: Vec<u8>,
    schemas: Vec<(String, String, Vec<u8>)>,
    message_count: u64,
    message_start_time: u64,
    message_end_time: u64,
}

impl McapWriter {
    pub(crate) fn create(path: &Path, opts: &WriterOptions) -> Result<Self, RecordingError> {
        let (chunk_size, zstd_level) = (opts.chunk_size_bytes, opts.zstd_level);
        let file = File::create(path).map_err(io_error(path, "creating"))?;
        let compressor =
            compressor(zstd_level).map_err(io_error(path, "setting up zstd compression"))?;
        let chunk_size = usize::try_from(chunk_size.clamp(1, 1 << 30)).unwrap_or(1 << 20);
        let side = Box::new(FileSide {
            out: Out {
                path: path.to_path_buf(),
                file: BufWriter::with_capacity(1 << 16, file),
                pos: 0,
                crc: crc32fast::Hasher::new(),
            },
            chunk_index_records: Vec::new(),
            attachment_index_records: Vec::new(),
            metadata_index_records: Vec::new(),
            chunk_count: 0,
            attachment_count: 0,
            metadata_count: 0,
            syncer: None,
        });
        let file = match spawn_workers(side, opts, path) {
            Ok(workers) => FileHandle::Workers(workers),
            Err(side) => FileHandle::Inline { side, compressor },
        };
        let mut mcap = Self {
            path: path.to_path_buf(),
            file,
            chunk_size,
            chunk: Vec::with_capacity(chunk_size + 4096),
            chunk_start_time: u64::MAX,
            chunk_end_time: 0,
            touched: Vec::new(),
            channels: Vec::new(),
            slot_of_id: HashMap::new(),
            schema_records: Vec::new(),
            channel_records: Vec::new(),
            schemas: Vec::new(),
            message_count: 0,
            message_start_time: u64::MAX,
            message_end_time: 0,
        };
        let mut b = MAGIC.to_vec();
        let at = begin_record(&mut b, op::HEADER);
        put_str(&mut b, ""); // profile: none of the well-known ones
        put_str(
            &mut b,
            concat!("gyrolab gyro-mcap ", env!("CARGO_PKG_VERSION")),
        );
        end_record(&mut b, at);
        mcap.submit(Job::Bytes(b))?;
        Ok(mcap)
    }

    pub(crate) fn path(&self) -> &Path {
        &self.path
    }

    pub(crate) fn message_count(&self) -> u64 {
        self.message_count
    }

    /// Hands a job to the file side (in order); a failure of the file side, now or earlier,
    /// comes back here.
    fn submit(&mut self, mut job: Job) -> Result<(), RecordingError> {
        match &mut self.file {
            FileHandle::Inline { side, compressor } => {
                let mut r = match &mut job {
                    Job::Chunk(c) => compress(compressor, c, &self.path),
                    _ => Ok(()),
                };
                if r.is_ok() {
                    r = side.apply(&mut job);
                }
                if let Job::Sync(reply) = job {
                    let _ = reply.send(r.is_ok());
                }
                r
            }
            FileHandle::Workers(w) => {
                let k = w.inputs.len();
                if w.failed.load(Ordering::Acquire) || w.inputs[w.next % k].send(job).is_err() {
                    return Err(self.worker_error());
                }
                w.next += 1;
                Ok(())
            }
            FileHandle::Gone => Err(self.gone()),
        }
    }

    /// Waits until everything submitted is written and handed to the operating system.
    fn sync(&mut self) -> Result<(), RecordingError> {
        let (reply, answer) = mpsc::sync_channel(1);
        self.submit(Job::Sync(reply))?;
        match answer.recv() {
            Ok(true) => Ok(()),
            _ => Err(self.worker_error()),
        }
    }

    /// Stops the worker and returns the file side, or the error that stopped it.
    fn join(&mut self) -> Result<Box<FileSide>, RecordingError> {
        match std::mem::replace(&mut self.file, FileHandle::Gone) {
            FileHandle::Inline { side, .. } => Ok(side),
            FileHandle::Workers(w) => {
                drop(w.inputs);
                for h in w.compressors {
                    let _ = h.join();
                }
                match w.writer.join() {
                    Ok((side, None)) => Ok(side),
                    Ok((_, Some(e))) => Err(e),
                    Err(_) => Err(RecordingError::Usage {
                        path: self.path.clone(),
                        call: "writing".into(),
                        expected: "a writer thread that does not panic".into(),
                    }),
                }
            }
            FileHandle::Gone => Err(self.gone()),
        }
    }

    /// The error that stopped the worker (it is joined; later calls get [`Self::gone`]).
    #[cold]
    fn worker_error(&mut self) -> RecordingError {
        match self.join() {
            Err(e) => e,
            Ok(_) => self.gone(),
        }
    }

    #[cold]
    fn gone(&self) -> RecordingError {
        self.usage(
            "writing",
            "a writer whose file has not failed or been finished",
        )
    }

    /// Adds a schema (or returns the id of an identical one). Ids start at 1.
    pub(crate) fn add_schema(
        &mut self,
        name: &str,
        encoding: &str,
        data: &[u8],
    ) -> Result<u16, RecordingError> {
        if let Some(i) = self
            .schemas
            .iter()
            .position(|(n, e, d)| n == name && e == encoding && d == data)
        {
            return Ok(i as u16 + 1);
        }
        let id = u16::try_from(self.schemas.len() + 1)
            .map_err(|_| self.usage("add schema", "at most 65535 schemas"))?;
        if data.len() > u32::MAX as usize {
            return Err(self.usage("add schema", "schema data below 4 GiB"));
        }
        let mut b = Vec::new();
        let at = begin_record(&mut b, op::SCHEMA);
        put_u16(&mut b, id);
        put_str(&mut b, name);
        put_str(&mut b, encoding);
        put_bytes32(&mut b, data);
        end_record(&mut b, at);
        self.schema_records.extend_from_slice(&b);
        self.submit(Job::Bytes(b))?;
        self.schemas
            .push((name.to_owned(), encoding.to_owned(), data.to_vec()));
        Ok(id)
    }

    /// Adds a channel with a given id; returns its slot.
    pub(crate) fn add_channel(
        &mut self,
        id: u16,
        schema_id: u16,
        topic: &str,
        message_encoding: &str,
        metadata: &BTreeMap<String, String>,
    ) -> Result<usize, RecordingError> {
        if self.slot_of_id.contains_key(&id) {
            return Err(self.usage("add channel", format!("a new channel id, {id} is taken")));
        }
        let mut b = Vec::new();
        let at = begin_record(&mut b, op::CHANNEL);
        put_u16(&mut b, id);
        put_u16(&mut b, schema_id);
        put_str(&mut b, topic);
        put_str(&mut b, message_encoding);
        put_str_map(&mut b, metadata);
        end_record(&mut b, at);
        self.channel_records.extend_from_slice(&b);
        self.submit(Job::Bytes(b))?;
        let slot = self.channels.len();
        self.channels.push(McapChannel {
            id,
            topic: topic.to_owned(),
            sequence: 0,
            message_count: 0,
            chunk_index: Vec::new(),
        });
        self.slot_of_id.insert(id, slot);
        Ok(slot)
    }

    pub(crate) fn slot_of(&self, id: u16) -> Option<usize> {
        self.slot_of_id.get(&id).copied()
    }

    pub(crate) fn topic(&self, slot: usize) -> &str {
        self.channels.get(slot).map_or("", |c| c.topic.as_str())
    }

    fn usage(&self, call: impl Into<String>, expected: impl Into<String>) -> RecordingError {
        RecordingError::Usage {
            path: self.path.clone(),
            call: call.into(),
            expected: expected.into(),
        }
    }

    /// Appends a message record's header to the open chunk and indexes it; the caller appends
    /// exactly `data_len` payload bytes to the returned buffer next.
    #[inline]
    pub(crate) fn begin_message(
        &mut self,
        slot: usize,
        sequence: Option<u32>,
        log_time: u64,
        publish_time: u64,
        data_len: usize,
    ) -> &mut Vec<u8> {
        let ch = &mut self.channels[slot];
        let offset = self.chunk.len() as u64;
        if ch.chunk_index.is_empty() {
            self.touched.push(slot);
        }
        let mut entry = [0u8; 16];
        entry[..8].copy_from_slice(&log_time.to_le_bytes());
        entry[8..].copy_from_slice(&offset.to_le_bytes());
        ch.chunk_index.extend_from_slice(&entry);
        let seq = sequence.unwrap_or(ch.sequence);
        ch.sequence = seq.wrapping_add(1);
        ch.message_count += 1;
        self.message_count += 1;
        self.chunk_start_time = self.chunk_start_time.min(log_time);
        self.chunk_end_time = self.chunk_end_time.max(log_time);
        let mut head = [0u8; 1 + 8 + 2 + 4 + 8 + 8];
        head[0] = op::MESSAGE;
        head[1..9].copy_from_slice(&((2 + 4 + 8 + 8 + data_len) as u64).to_le_bytes());
        head[9..11].copy_from_slice(&ch.id.to_le_bytes());
        head[11..15].copy_from_slice(&seq.to_le_bytes());
        head[15..23].copy_from_slice(&log_time.to_le_bytes());
        head[23..31].copy_from_slice(&publish_time.to_le_bytes());
        self.chunk.reserve(head.len() + data_len);
        self.chunk.extend_from_slice(&head);
        &mut self.chunk
    }

    pub(crate) fn chunk_is_full(&self) -> bool {
        self.chunk.len() >= self.chunk_size
    }

    /// Closes the open chunk and queues it for compression and writing; returns at once (the
    /// worker writes it within milliseconds). A failed earlier write is reported here.
    pub(crate) fn close_chunk(&mut self) -> Result<(), RecordingError> {
        if self.chunk.is_empty() {
            return Ok(());
        }
        let mut job = match &self.file {
            FileHandle::Workers(w) => w.recycled.try_recv().ok(),
            _ => None,
        }
        .unwrap_or_default();
        if job.records.capacity() == 0 {
            job.records.reserve(self.chunk_size + 4096);
        }
        std::mem::swap(&mut job.records, &mut self.chunk);
        job.start_time = self.chunk_start_time;
        job.end_time = self.chunk_end_time;
        // Message indexes, one per channel in this chunk.
        for &slot in &self.touched {
            let ch = &mut self.channels[slot];
            job.index_offsets.push((ch.id, job.indexes.len() as u64));
            let b = &mut job.indexes;
            b.push(op::MESSAGE_INDEX);
            put_u64(b, (2 + 4 + ch.chunk_index.len()) as u64);
            put_u16(b, ch.id);
            put_u32(b, len32(ch.chunk_index.len()));
            b.extend_from_slice(&ch.chunk_index);
            ch.chunk_index.clear();
        }
        self.touched.clear();
        self.message_start_time = self.message_start_time.min(self.chunk_start_time);
        self.message_end_time = self.message_end_time.max(self.chunk_end_time);
        self.chunk_start_time = u64::MAX;
        self.chunk_end_time = 0;
        self.submit(Job::Chunk(job))
    }

    /// Closes the open chunk and waits until it (and everything before it) is written and
    /// handed to the operating system, so it survives the process being killed.
    pub(crate) fn flush_chunk(&mut self) -> Result<(), RecordingError> {
        self.close_chunk()?;
        self.sync()
    }

    pub(crate) fn write_metadata(
        &mut self,
        name: &str,
        entries: &BTreeMap<String, String>,
    ) -> Result<(), RecordingError> {
        let mut b = Vec::new();
        let at = begin_record(&mut b, op::METADATA);
        put_str(&mut b, name);
        put_str_map(&mut b, entries);
        end_record(&mut b, at);
        self.submit(Job::Metadata {
            record: b,
            name: name.to_owned(),
        })
    }

    pub(crate) fn attach(
        &mut self,
        name: &str,
        media_type: &str,
        log_time: u64,
        create_time: u64,
        data: &[u8],
    ) -> Result<(), RecordingError> {
        let mut b = Vec::with_capacity(data.len() + 64 + name.len() + media_type.len());
        let at = begin_record(&mut b, op::ATTACHMENT);
        put_u64(&mut b, log_time);
        put_u64(&mut b, create_time);
        put_str(&mut b, name);
        put_str(&mut b, media_type);
        put_u64(&mut b, data.len() as u64);
        b.extend_from_slice(data);
        let crc = crc32fast::hash(&b[at + 8..]);
        put_u32(&mut b, crc);
        end_record(&mut b, at);
        self.submit(Job::Attachment {
            record: b,
            log_time,
            create_time,
            data_len: data.len() as u64,
            name: name.to_owned(),
            media_type: media_type.to_owned(),
        })
    }

    /// Writes the last chunk, DataEnd, the summary section with its offsets, the footer and the
    /// closing magic; syncs the file to disk. Returns the file size.
    pub(crate) fn finish(&mut self) -> Result<u64, RecordingError> {
        self.close_chunk()?;
        let mut side = self.join()?;
        if let Some(s) = side.syncer.take() {
            s.stop()
                .map_err(io_error(&side.out.path, "syncing to disk"))?;
        }
        let out = &mut side.out;
        let data_crc = out.crc.clone().finalize();
        let mut b = Vec::new();
        let at = begin_record(&mut b, op::DATA_END);
        put_u32(&mut b, data_crc);
        end_record(&mut b, at);
        out.emit(&b)?;
        // The summary CRC covers the summary section and the footer up to its CRC field.
        out.crc = crc32fast::Hasher::new();

        // Summary: each group, remembering where it went for the summary offsets.
        let summary_start = out.pos;
        let mut statistics = Vec::new();
        let at = begin_record(&mut statistics, op::STATISTICS);
        put_u64(&mut statistics, self.message_count);
        put_u16(&mut statistics, self.schemas.len() as u16);
        put_u32(&mut statistics, self.channels.len() as u32);
        put_u32(&mut statistics, side.attachment_count);
        put_u32(&mut statistics, side.metadata_count);
        put_u32(&mut statistics, side.chunk_count);
        let (start, end) = if self.message_count == 0 {
            (0, 0)
        } else {
            (self.message_start_time, self.message_end_time)
        };
        put_u64(&mut statistics, start);
        put_u64(&mut statistics, end);
        let map_at = statistics.len();
        put_u32(&mut statistics, 0);
        for ch in &self.channels {
            put_u16(&mut statistics, ch.id);
            put_u64(&mut statistics, ch.message_count);
        }
        let map_len = statistics.len() - map_at - 4;
        patch_u32(&mut statistics, map_at, map_len);
        end_record(&mut statistics, at);

        let groups = [
            (op::SCHEMA, std::mem::take(&mut self.schema_records)),
            (op::CHANNEL, std::mem::take(&mut self.channel_records)),
            (op::STATISTICS, statistics),
            (
                op::CHUNK_INDEX,
                std::mem::take(&mut side.chunk_index_records),
            ),
            (
                op::ATTACHMENT_INDEX,
                std::mem::take(&mut side.attachment_index_records),
            ),
            (
                op::METADATA_INDEX,
                std::mem::take(&mut side.metadata_index_records),
            ),
        ];
        let out = &mut side.out;
        let mut offsets = Vec::new();
        for (opcode, bytes) in &groups {
            if bytes.is_empty() {
                continue;
            }
            let at = begin_record(&mut offsets, op::SUMMARY_OFFSET);
            offsets.push(*opcode);
            put_u64(&mut offsets, out.pos);
            put_u64(&mut offsets, bytes.len() as u64);
            end_record(&mut offsets, at);
            out.emit(bytes)?;
        }
        let summary_offset_start = out.pos;
        out.emit(&offsets)?;
        let mut footer = Vec::new();
        footer.push(op::FOOTER);
        put_u64(&mut footer, 8 + 8 + 4);
        put_u64(&mut footer, summary_start);
        put_u64(&mut footer, summary_offset_start);
        out.emit(&footer)?;
        let summary_crc = out.crc.clone().finalize();
        out.emit(&summary_crc.to_le_bytes())?;
        out.emit(MAGIC)?;
        out.file.flush().map_err(io_error(&out.path, "flushing"))?;
        out.file
            .get_ref()
            .sync_all()
            .map_err(io_error(&out.path, "syncing to disk"))?;
        Ok(out.pos)
    }
}

impl Drop for McapWriter {
    /// Lets the worker write what it was given (the open chunk is the owner's business).
    fn drop(&mut self) {
        let _ = self.join();
    }
}

/// How a channel's messages are encoded, fixed when it is added.
enum ChannelEncoder {
    Record {
        kinds: Vec<FieldKind>,
        tags: Vec<Tag>,
        /// When every field is F64 (the fast path): the encoded message with every value 0.0,
        /// and where each value's 8 bytes go in it. Else None.
        all_f64: Option<F64Template>,
    },
    Pose,
}

/// A record of F64 fields only, encoded once with zeros: a message is this copy with its values
/// patched in.
struct F64Template {
    bytes: Vec<u8>,
    value_at: Vec<usize>,
}

/// Writes one recording: `<final_path>.partial` while running, renamed to `final_path` by
/// [`finish`](Self::finish). Dropping it without `finish` closes the open chunk (best effort) and
/// leaves the `.partial` file for [`crate::recover`].
pub struct RecordingWriter {
    mcap: McapWriter,
    final_path: PathBuf,
    encoders: Vec<ChannelEncoder>,
    flush_interval_s: f64,
    last_flush: Instant,
    since_clock_check: u32,
    finished: bool,
}

/// How many messages between two looks at the clock (a look costs ~20 ns).
const CLOCK_CHECK_EVERY: u32 = 256;

impl RecordingWriter {
    /// Opens `<final_path>.partial` for writing; `finish` renames it to `final_path`.
    pub fn create(final_path: &Path, opts: WriterOptions) -> Result<Self, RecordingError> {
        let partial = partial_path(final_path);
        let mcap = McapWriter::create(&partial, &opts)?;
        Ok(Self {
            mcap,
            final_path: final_path.to_path_buf(),
            encoders: Vec::new(),
            flush_interval_s: if opts.flush_interval_s.is_finite() {
                opts.flush_interval_s.max(0.0)
            } else {
                1.0
            },
            last_flush: Instant::now(),
            since_clock_check: 0,
            finished: false,
        })
    }

    /// The `.partial` path being written.
    pub fn partial_path(&self) -> &Path {
        self.mcap.path()
    }

    fn next_channel_id(&self, topic: &str) -> Result<u16, RecordingError> {
        if (0..self.encoders.len()).any(|slot| self.mcap.topic(slot) == topic) {
            return Err(self.usage(
                format!("adding channel {topic:?}"),
                "a topic not used by another channel",
            ));
        }
        u16::try_from(self.encoders.len() + 1).map_err(|_| {
            self.usage(
                format!("adding channel {topic:?}"),
                "at most 65535 channels",
            )
        })
    }

    /// A channel of flat records (see [`RecordSchema`]); the schema is the record's proto3
    /// FileDescriptorSet; field units go to the channel metadata as `unit.<field>`.
    pub fn add_record_channel(
        &mut self,
        topic: &str,
        schema: &RecordSchema,
    ) -> Result<ChannelId, RecordingError> {
        schema
            .validate()
            .map_err(|e| self.usage(format!("adding channel {topic:?}"), e))?;
        let id = self.next_channel_id(topic)?;
        let schema_id =
            self.mcap
                .add_schema(&schema.full_name, "protobuf", &schema.file_descriptor_set())?;
        let metadata: BTreeMap<String, String> = schema
            .fields
            .iter()
            .filter_map(|f| Some((format!("unit.{}", f.name), f.unit.clone()?)))
            .collect();
        let slot = self
            .mcap
            .add_channel(id, schema_id, topic, "protobuf", &metadata)?;
        let kinds: Vec<FieldKind> = schema.fields.iter().map(|f| f.kind).collect();
        let tags = kinds
            .iter()
            .enumerate()
            .map(|(i, k)| {
                let wire = match k {
                    FieldKind::F64 => WIRE_FIXED64,
                    FieldKind::U64 => WIRE_VARINT,
                    FieldKind::Str => WIRE_LEN,
                };
                Tag::new(i as u32 + 1, wire)
            })
            .collect::<Vec<_>>();
        let all_f64 = kinds.iter().all(|k| *k == FieldKind::F64).then(|| {
            let mut bytes = Vec::new();
            let mut value_at = Vec::new();
            for t in &tags {
                bytes.extend_from_slice(t.as_slice());
                value_at.push(bytes.len());
                bytes.extend_from_slice(&[0; 8]);
            }
            F64Template { bytes, value_at }
        });
        self.encoders.push(ChannelEncoder::Record {
            kinds,
            tags,
            all_f64,
        });
        Ok(ChannelId(slot as u32))
    }

    /// A channel of `foxglove.FrameTransform` poses (protobuf; the schema is its FileDescriptorSet).
    pub fn add_pose_channel(&mut self, topic: &str) -> Result<ChannelId, RecordingError> {
        let id = self.next_channel_id(topic)?;
        let schema_id = self
            .mcap
            .add_schema(POSE_SCHEMA_NAME, "protobuf", FRAME_TRANSFORM_FDS)?;
        let slot = self
            .mcap
            .add_channel(id, schema_id, topic, "protobuf", &BTreeMap::new())?;
        self.encoders.push(ChannelEncoder::Pose);
        Ok(ChannelId(slot as u32))
    }

    fn usage(&self, call: impl Into<String>, expected: impl Into<String>) -> RecordingError {
        RecordingError::Usage {
            path: self.mcap.path().to_path_buf(),
            call: call.into(),
            expected: expected.into(),
        }
    }

    fn channel(&self, ch: ChannelId, call: &str) -> Result<&ChannelEncoder, RecordingError> {
        self.encoders
            .get(ch.0 as usize)
            .ok_or_else(|| self.usage(call, "a channel id returned by this writer"))
    }

    /// Fast path: every field of the channel is F64; `values` in schema order.
    pub fn write_f64_record(
        &mut self,
        ch: ChannelId,
        log_time_ns: u64,
        values: &[f64],
    ) -> Result<(), RecordingError> {
        let slot = ch.0 as usize;
        let template = match self.encoders.get(slot) {
            Some(ChannelEncoder::Record {
                all_f64: Some(t), ..
            }) if t.value_at.len() == values.len() => t,
            _ => return Err(self.f64_misuse(ch, values.len())),
        };
        let buf =
            self.mcap
                .begin_message(slot, None, log_time_ns, log_time_ns, template.bytes.len());
        let start = buf.len();
        buf.extend_from_slice(&template.bytes);
        let msg = &mut buf[start..];
        for (&at, v) in template.value_at.iter().zip(values) {
            msg[at..at + 8].copy_from_slice(&v.to_le_bytes());
        }
        self.after_message()
    }

    #[cold]
    fn f64_misuse(&self, ch: ChannelId, n: usize) -> RecordingError {
        let topic = self.mcap.topic(ch.0 as usize).to_owned();
        let call = format!("write_f64_record on {topic:?}");
        match self.encoders.get(ch.0 as usize) {
            None => self.usage(call, "a channel id returned by this writer"),
            Some(ChannelEncoder::Pose) => {
                self.usage(call, "a record channel, found a pose channel")
            }
            Some(ChannelEncoder::Record { all_f64: None, .. }) => self.usage(
                call,
                "a channel whose fields are all F64 (use write_record)",
            ),
            Some(ChannelEncoder::Record { tags, .. }) => {
                self.usage(call, format!("{} values, found {n}", tags.len()))
            }
        }
    }

    /// Any record: `values` in schema order, each of its field's kind.
    pub fn write_record(
        &mut self,
        ch: ChannelId,
        log_time_ns: u64,
        values: &[Value],
    ) -> Result<(), RecordingError> {
        let slot = ch.0 as usize;
        let call = "write_record";
        let Some(ChannelEncoder::Record { kinds, tags, .. }) = self.encoders.get(slot) else {
            let what = if self.encoders.get(slot).is_some() {
                "a record channel, found a pose channel"
            } else {
                "a channel id returned by this writer"
            };
            return Err(self.usage(call, what));
        };
        if kinds.len() != values.len() {
            let topic = self.mcap.topic(slot);
            return Err(self.usage(
                format!("write_record on {topic:?}"),
                format!("{} values, found {}", kinds.len(), values.len()),
            ));
        }
        let mut len = 0usize;
        for (i, (kind, v)) in kinds.iter().zip(values).enumerate() {
            len += tags[i].len()
                + match (kind, v) {
                    (FieldKind::F64, Value::F64(_)) => 8,
                    (FieldKind::U64, Value::U64(x)) => varint_len(*x),
                    (FieldKind::Str, Value::Str(s)) => varint_len(s.len() as u64) + s.len(),
                    _ => {
                        let topic = self.mcap.topic(slot);
                        return Err(self.usage(
                            format!("write_record on {topic:?}"),
                            format!("value {i} of kind {kind:?}, found {v:?}"),
                        ));
                    }
                };
        }
        let buf = self
            .mcap
            .begin_message(slot, None, log_time_ns, log_time_ns, len);
        for (tag, v) in tags.iter().zip(values) {
            buf.extend_from_slice(tag.as_slice());
            match v {
                Value::F64(x) => buf.extend_from_slice(&x.to_le_bytes()),
                Value::U64(x) => put_varint(buf, *x),
                Value::Str(s) => {
                    put_varint(buf, s.len() as u64);
                    buf.extend_from_slice(s.as_bytes());
                }
            }
        }
        self.after_message()
    }

    /// One pose on a pose channel; its `timestamp` field is `log_time_ns`.
    pub fn write_pose(
        &mut self,
        ch: ChannelId,
        log_time_ns: u64,
        pose: &Pose,
    ) -> Result<(), RecordingError> {
        let slot = ch.0 as usize;
        if !matches!(self.channel(ch, "write_pose")?, ChannelEncoder::Pose) {
            let topic = self.mcap.topic(slot);
            return Err(self.usage(
                format!("write_pose on {topic:?}"),
                "a pose channel, found a record channel",
            ));
        }
        let len = pose_encoded_len(log_time_ns, pose);
        let buf = self
            .mcap
            .begin_message(slot, None, log_time_ns, log_time_ns, len);
        let start = buf.len();
        buf.resize(start + len, 0);
        encode_pose(&mut buf[start..], log_time_ns, pose);
        self.after_message()
    }

    #[inline]
    fn after_message(&mut self) -> Result<(), RecordingError> {
        if self.mcap.chunk_is_full() {
            return self.close_chunk();
        }
        self.since_clock_check += 1;
        if self.since_clock_check >= CLOCK_CHECK_EVERY {
            self.since_clock_check = 0;
            if self.last_flush.elapsed().as_secs_f64() >= self.flush_interval_s {
                return self.close_chunk();
            }
        }
        Ok(())
    }

    /// Closes the open chunk and queues it for the writer thread (no waiting).
    fn close_chunk(&mut self) -> Result<(), RecordingError> {
        self.last_flush = Instant::now();
        self.since_clock_check = 0;
        self.mcap.close_chunk()
    }

    /// Closes the open chunk now and returns once it (and everything before it) is written and
    /// handed to the operating system. The writer also closes chunks by itself when one is full
    /// or `flush_interval_s` has passed; those are compressed and written by its thread while
    /// the caller goes on.
    pub fn flush_chunk(&mut self) -> Result<(), RecordingError> {
        self.last_flush = Instant::now();
        self.since_clock_check = 0;
        self.mcap.flush_chunk()
    }

    /// A named metadata record (e.g. "scene" → its TOML text and settings).
    pub fn write_metadata(
        &mut self,
        name: &str,
        entries: &BTreeMap<String, String>,
    ) -> Result<(), RecordingError> {
        self.mcap.write_metadata(name, entries)
    }

    /// An attachment (e.g. the scene file). Its create time is recorded as 0.
    pub fn attach(
        &mut self,
        name: &str,
        media_type: &str,
        log_time_ns: u64,
        data: &[u8],
    ) -> Result<(), RecordingError> {
        self.mcap.attach(name, media_type, log_time_ns, 0, data)
    }

    /// Writes the summary and indexes, syncs, and renames `.partial` to the final path. Callable at
    /// any point of a run (e.g. after Ctrl-C).
    pub fn finish(mut self) -> Result<WriteSummary, RecordingError> {
        self.finished = true;
        let bytes = self.mcap.finish()?;
        let partial = self.mcap.path().to_path_buf();
        std::fs::rename(&partial, &self.final_path)
            .map_err(io_error(&partial, "renaming to the final name"))?;
        if let Some(dir) = self.final_path.parent() {
            // Make the rename durable where the platform allows opening a directory.
            if let Ok(d) = File::open(if dir.as_os_str().is_empty() {
                Path::new(".")
            } else {
                dir
            }) {
                let _ = d.sync_all();
            }
        }
        Ok(WriteSummary {
            path: self.final_path.clone(),
            bytes,
            messages: self.mcap.message_count(),
        })
    }
}

impl Drop for RecordingWriter {
    fn drop(&mut self) {
        if !self.finished {
            // Best effort: keep what was written so far for `recover`.
            let _ = self.mcap.flush_chunk();
        }
    }
}

/// `<path>.partial`.
pub fn partial_path(final_path: &Path) -> PathBuf {
    let mut s = final_path.as_os_str().to_owned();
    s.push(".partial");
    PathBuf::from(s)
}

impl McapWriter {
    /// Re-emits a raw message (used by `recover`).
    pub(crate) fn write_raw(
        &mut self,
        slot: usize,
        sequence: u32,
        log_time: u64,
        publish_time: u64,
        data: &[u8],
    ) -> Result<(), RecordingError> {
        let buf = self.begin_message(slot, Some(sequence), log_time, publish_time, data.len());
        buf.extend_from_slice(data);
        if self.chunk_is_full() {
            self.close_chunk()?;
        }
        Ok(())
    }
}
