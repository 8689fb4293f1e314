//! Decoding protobuf payloads: flat records through a layout read from the schema's
//! FileDescriptorSet, and `foxglove.FrameTransform` by hand. Untrusted bytes: every length and
//! varint is bounds-checked; errors are strings the caller places in a `RecordingError`.

use prost::Message as _;
use prost_types::field_descriptor_proto::{Label, Type};
use prost_types::{DescriptorProto, FileDescriptorSet};

use crate::schema::{WIRE_FIXED32, WIRE_FIXED64, WIRE_LEN, WIRE_VARINT};

/// A column being filled.
#[derive(Debug, Clone, PartialEq)]
pub enum Column {
    F64(Vec<f64>),
    U64(Vec<u64>),
    Str(Vec<String>),
}

impl Column {
    pub fn len(&self) -> usize {
        match self {
            Column::F64(v) => v.len(),
            Column::U64(v) => v.len(),
            Column::Str(v) => v.len(),
        }
    }
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }
    pub fn as_f64(&self) -> Option<&[f64]> {
        match self {
            Column::F64(v) => Some(v),
            _ => None,
        }
    }
    pub fn as_u64(&self) -> Option<&[u64]> {
        match self {
            Column::U64(v) => Some(v),
            _ => None,
        }
    }
    pub fn as_str(&self) -> Option<&[String]> {
        match self {
            Column::Str(v) => Some(v),
            _ => None,
        }
    }
    fn push_default(&mut self) {
        match self {
            Column::F64(v) => v.push(0.0),
            Column::U64(v) => v.push(0),
            Column::Str(v) => v.push(String::new()),
        }
    }
    pub(crate) fn permute(&mut self, order: &[usize]) {
        fn apply<T: Clone>(v: &mut Vec<T>, order: &[usize]) {
            *v = order.iter().map(|&i| v[i].clone()).collect();
        }
        match self {
            Column::F64(v) => apply(v, order),
            Column::U64(v) => apply(v, order),
            Column::Str(v) => apply(v, order),
        }
    }
}

/// How one protobuf field becomes a column.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Decoding {
    Double,
    Float,
    Varint,
    Fixed64,
    Fixed32,
    Bool,
    Str,
}

impl Decoding {
    fn wire(self) -> u32 {
        match self {
            Decoding::Double | Decoding::Fixed64 => WIRE_FIXED64,
            Decoding::Float | Decoding::Fixed32 => WIRE_FIXED32,
            Decoding::Varint | Decoding::Bool => WIRE_VARINT,
            Decoding::Str => WIRE_LEN,
        }
    }
    fn empty_column(self) -> Column {
        match self {
            Decoding::Double | Decoding::Float => Column::F64(Vec::new()),
            Decoding::Varint | Decoding::Fixed64 | Decoding::Fixed32 | Decoding::Bool => {
                Column::U64(Vec::new())
            }
            Decoding::Str => Column::Str(Vec::new()),
        }
    }
}

/// The columns of a flat message type, from its descriptor.
#[derive(Debug, Clone)]
pub(crate) struct RecordLayout {
    pub names: Vec<String>,
    decodings: Vec<Decoding>,
    /// Field number → column, for numbers up to `MAX_INDEXED_NUMBER`.
    by_number: Vec<Option<u32>>,
}

const MAX_INDEXED_NUMBER: i32 = 1 << 16;

impl RecordLayout {
    /// The layout of message `full_name` in an encoded FileDescriptorSet. Singular double, float,
    /// uint64, uint32, fixed64, fixed32, bool and string fields become columns; other fields
    /// (signed integers, enums, bytes, messages, repeated) are skipped when decoding.
    pub(crate) fn from_descriptor_set(fds: &[u8], full_name: &str) -> Result<Self, String> {
        let set = FileDescriptorSet::decode(fds)
            .map_err(|e| format!("a protobuf FileDescriptorSet as schema data ({e})"))?;
        let message = find_message(&set, full_name).ok_or_else(|| {
            format!("message type {full_name:?} in the schema's FileDescriptorSet")
        })?;
        let mut layout = RecordLayout {
            names: Vec::new(),
            decodings: Vec::new(),
            by_number: Vec::new(),
        };
        for field in &message.field {
            if field.label == Some(Label::Repeated as i32) {
                continue;
            }
            let decoding = match field.r#type.and_then(|t| Type::try_from(t).ok()) {
                Some(Type::Double) => Decoding::Double,
                Some(Type::Float) => Decoding::Float,
                Some(Type::Uint64 | Type::Uint32) => Decoding::Varint,
                Some(Type::Fixed64) => Decoding::Fixed64,
                Some(Type::Fixed32) => Decoding::Fixed32,
                Some(Type::Bool) => Decoding::Bool,
                Some(Type::String) => Decoding::Str,
                _ => continue,
            };
            let number = field.number.unwrap_or(0);
            if !(1..=MAX_INDEXED_NUMBER).contains(&number) {
                continue;
            }
            let number = number as usize;
            if layout.by_number.len() <= number {
                layout.by_number.resize(number + 1, None);
            }
            if layout.by_number[number].is_some() {
                return Err(format!("field number {number} used once in {full_name:?}"));
            }
            layout.by_number[number] = Some(layout.names.len() as u32);
            layout.names.push(field.name.clone().unwrap_or_default());
            layout.decodings.push(decoding);
        }
        Ok(layout)
    }

    pub(crate) fn empty_columns(&self) -> Vec<Column> {
        self.decodings.iter().map(|d| d.empty_column()).collect()
    }

    /// Appends one row decoded from `data` (missing fields: their default).
    pub(crate) fn decode_into(&self, data: &[u8], columns: &mut [Column]) -> Result<(), String> {
        for c in columns.iter_mut() {
            c.push_default();
        }
        let mut r = Wire::new(data);
        while !r.done() {
            let (number, wire) = r.key()?;
            let slot = self.by_number.get(number as usize).copied().flatten();
            let Some(col) = slot else {
                r.skip(wire)?;
                continue;
            };
            let col = col as usize;
            let decoding = self.decodings[col];
            if decoding.wire() != wire {
                return Err(format!(
                    "field {:?} (number {number}) with wire type {}, found {wire}",
                    self.names[col],
                    decoding.wire()
                ));
            }
            match (&mut columns[col], decoding) {
                (Column::F64(v), Decoding::Double) => set_last(v, f64::from_bits(r.fixed64()?)),
                (Column::F64(v), Decoding::Float) => {
                    set_last(v, f64::from(f32::from_bits(r.fixed32()?)))
                }
                (Column::U64(v), Decoding::Varint) => set_last(v, r.varint()?),
                (Column::U64(v), Decoding::Bool) => set_last(v, u64::from(r.varint()? != 0)),
                (Column::U64(v), Decoding::Fixed64) => set_last(v, r.fixed64()?),
                (Column::U64(v), Decoding::Fixed32) => set_last(v, u64::from(r.fixed32()?)),
                (Column::Str(v), Decoding::Str) => {
                    let s = std::str::from_utf8(r.len_delimited()?)
                        .map_err(|_| format!("field {:?} as UTF-8 text", self.names[col]))?;
                    if let Some(last) = v.last_mut() {
                        last.clear();
                        last.push_str(s);
                    }
                }
                _ => return Err("columns that match the layout".to_owned()),
            }
        }
        Ok(())
    }
}

fn set_last<T>(v: &mut [T], x: T) {
    if let Some(last) = v.last_mut() {
        *last = x;
    }
}

fn find_message<'a>(set: &'a FileDescriptorSet, full_name: &str) -> Option<&'a DescriptorProto> {
    let full_name = full_name.strip_prefix('.').unwrap_or(full_name);
    set.file.iter().find_map(|file| {
        let package = file.package.as_deref().unwrap_or("");
        let rest = if package.is_empty() {
            full_name
        } else {
            full_name.strip_prefix(package)?.strip_prefix('.')?
        };
        // Top-level or nested (Outer.Inner) message types.
        let mut parts = rest.split('.');
        let first = parts.next()?;
        let mut message = file
            .message_type
            .iter()
            .find(|m| m.name.as_deref() == Some(first))?;
        for part in parts {
            message = message
                .nested_type
                .iter()
                .find(|m| m.name.as_deref() == Some(part))?;
        }
        Some(message)
    })
}

/// A protobuf wire-format reader over untrusted bytes.
pub(crate) struct Wire<'a> {
    data: &'a [u8],
    pos: usize,
}

impl<'a> Wire<'a> {
    pub(crate) fn new(data: &'a [u8]) -> Self {
        Self { data, pos: 0 }
    }
    pub(crate) fn done(&self) -> bool {
        self.pos >= self.data.len()
    }
    pub(crate) fn varint(&mut self) -> Result<u64, String> {
        let mut v = 0u64;
        for i in 0..10 {
            let Some(&b) = self.data.get(self.pos) else {
                return Err(format!(
                    "a varint, found the end of the message at byte {}",
                    self.pos
                ));
            };
            self.pos += 1;
            v |= u64::from(b & 0x7F) << (7 * i);
            if b < 0x80 {
                return Ok(v);
            }
        }
        Err(format!(
            "a varint of at most 10 bytes before byte {}",
            self.pos
        ))
    }
    pub(crate) fn key(&mut self) -> Result<(u32, u32), String> {
        let key = self.varint()?;
        let number = key >> 3;
        if number == 0 || number > u64::from(u32::MAX >> 3) {
            return Err(format!("a field number from 1 to 2^29-1, found {number}"));
        }
        Ok((number as u32, (key & 7) as u32))
    }
    fn bytes(&mut self, n: usize) -> Result<&'a [u8], String> {
        if n > self.data.len() - self.pos {
            return Err(format!(
                "{n} bytes at byte {} of the message, found {}",
                self.pos,
                self.data.len() - self.pos
            ));
        }
        let s = &self.data[self.pos..self.pos + n];
        self.pos += n;
        Ok(s)
    }
    pub(crate) fn fixed64(&mut self) -> Result<u64, String> {
        let mut a = [0u8; 8];
        a.copy_from_slice(self.bytes(8)?);
        Ok(u64::from_le_bytes(a))
    }
    pub(crate) fn fixed32(&mut self) -> Result<u32, String> {
        let mut a = [0u8; 4];
        a.copy_from_slice(self.bytes(4)?);
        Ok(u32::from_le_bytes(a))
    }
    pub(crate) fn len_delimited(&mut self) -> Result<&'a [u8], String> {
        let n = self.varint()?;
        let n = usize::try_from(n).unwrap_or(usize::MAX);
        self.bytes(n)
    }
    pub(crate) fn skip(&mut self, wire: u32) -> Result<(), String> {
        match wire {
            WIRE_VARINT => self.varint().map(drop),
            WIRE_FIXED64 => self.bytes(8).map(drop),
            WIRE_LEN => self.len_delimited().map(drop),
            WIRE_FIXED32 => self.bytes(4).map(drop),
            other => Err(format!(
                "wire type 0, 1, 2 or 5 (groups are not supported), found {other}"
            )),
        }
    }
}

/// One decoded `foxglove.FrameTransform`.
pub(crate) struct DecodedPose<'a> {
    pub parent: &'a str,
    pub child: &'a str,
    pub translation: [f64; 3],
    pub rotation: [f64; 4],
}

fn decode_doubles<const N: usize>(data: &[u8], what: &str) -> Result<[f64; N], String> {
    let mut out = [0.0; N];
    let mut r = Wire::new(data);
    while !r.done() {
        let (number, wire) = r.key()?;
        let i = number as usize;
        if (1..=N).contains(&i) {
            if wire != WIRE_FIXED64 {
                return Err(format!(
                    "{what} field {number} as a double, found wire type {wire}"
                ));
            }
            out[i - 1] = f64::from_bits(r.fixed64()?);
        } else {
            r.skip(wire)?;
        }
    }
    Ok(out)
}

/// Decodes a FrameTransform; a missing rotation is the identity, missing numbers are zero.
pub(crate) fn decode_pose(data: &[u8]) -> Result<DecodedPose<'_>, String> {
    let mut pose = DecodedPose {
        parent: "",
        child: "",
        translation: [0.0; 3],
        rotation: [0.0, 0.0, 0.0, 1.0],
    };
    let mut r = Wire::new(data);
    while !r.done() {
        let (number, wire) = r.key()?;
        if (2..=5).contains(&number) && wire != WIRE_LEN {
            return Err(format!(
                "field {number} length-delimited, found wire type {wire}"
            ));
        }
        match number {
            2 | 3 => {
                let s = std::str::from_utf8(r.len_delimited()?)
                    .map_err(|_| "frame ids as UTF-8 text".to_owned())?;
                if number == 2 {
                    pose.parent = s;
                } else {
                    pose.child = s;
                }
            }
            4 => pose.translation = decode_doubles(r.len_delimited()?, "translation")?,
            5 => pose.rotation = decode_doubles(r.len_delimited()?, "rotation")?,
            _ => r.skip(wire)?,
        }
    }
    Ok(pose)
}
