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
    /// Appends the values of `other`, a column of the same kind (other kinds are ignored).
    pub(crate) fn append(&mut self, other: Column) {
        match (self, other) {
            (Column::F64(a), Column::F64(mut b)) => a.append(&mut b),
            (Column::U64(a), Column::U64(mut b)) => a.append(&mut b),
            (Column::Str(a), Column::Str(mut b)) => a.append(&mut b),
            _ => {}
        }
    }
    fn pop(&mut self) {
        match self {
            Column::F64(v) => drop(v.pop()),
            Column::U64(v) => drop(v.pop()),
            Column::Str(v) => drop(v.pop()),
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
    /// (key, column) of every column by increasing field number: the order in which our writer
    /// (and protobuf encoders generally) write fields, tried first by [`Self::decode_row`].
    canonical: Vec<(u64, u32)>,
}

const MAX_INDEXED_NUMBER: i32 = 1 << 16;

/// Values (8 bytes each) that the decoders of one read may reserve up front however small the
/// file: counts come from an untrusted file's indexes, so reservations are bounded by this or by
/// twice the file's bytes, whichever is larger (see `Recording::reserve_budget`); beyond it
/// vectors grow with the data.
pub(crate) const MAX_RESERVED_VALUES: usize = 1 << 24;

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
            canonical: Vec::new(),
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
        layout.canonical = layout
            .by_number
            .iter()
            .enumerate()
            .filter_map(|(number, col)| {
                let col = (*col)?;
                let wire = layout.decodings[col as usize].wire();
                Some((((number as u64) << 3) | u64::from(wire), col))
            })
            .collect();
        Ok(layout)
    }

    /// Appends one row decoded from `data`: first as the canonical encoding (every column once,
    /// by increasing field number, nothing else), which is one pass with no lookups; anything
    /// else goes through [`Self::decode_into`].
    #[inline]
    pub(crate) fn decode_row(&self, data: &[u8], columns: &mut [Column]) -> Result<(), String> {
        let mut r = Wire::new(data);
        let mut pushed = 0;
        for &(key, col) in &self.canonical {
            if !r.expect_key(key) {
                break;
            }
            let col = col as usize;
            let ok = match (&mut columns[col], self.decodings[col]) {
                (Column::F64(v), Decoding::Double) => {
                    r.fixed64().map(|x| v.push(f64::from_bits(x))).is_ok()
                }
                (Column::F64(v), Decoding::Float) => r
                    .fixed32()
                    .map(|x| v.push(f64::from(f32::from_bits(x))))
                    .is_ok(),
                (Column::U64(v), Decoding::Varint) => r.varint().map(|x| v.push(x)).is_ok(),
                (Column::U64(v), Decoding::Bool) => {
                    r.varint().map(|x| v.push(u64::from(x != 0))).is_ok()
                }
                (Column::U64(v), Decoding::Fixed64) => r.fixed64().map(|x| v.push(x)).is_ok(),
                (Column::U64(v), Decoding::Fixed32) => {
                    r.fixed32().map(|x| v.push(u64::from(x))).is_ok()
                }
                (Column::Str(v), Decoding::Str) => match r.len_delimited() {
                    Ok(b) => match std::str::from_utf8(b) {
                        Ok(s) => {
                            v.push(s.to_owned());
                            true
                        }
                        Err(_) => false,
                    },
                    Err(_) => false,
                },
                _ => false,
            };
            if !ok {
                break;
            }
            pushed += 1;
        }
        if pushed == self.canonical.len() && r.done() {
            return Ok(());
        }
        // Not canonical: undo and decode field by field.
        for &(_, col) in &self.canonical[..pushed] {
            columns[col as usize].pop();
        }
        self.decode_into(data, columns)
    }

    /// 8-byte words one row takes in the columns (the log time not counted; a string column's
    /// `String` takes three before its text).
    pub(crate) fn values_per_row(&self) -> usize {
        self.decodings
            .iter()
            .map(|d| match d.empty_column() {
                Column::Str(_) => 3,
                Column::F64(_) | Column::U64(_) => 1,
            })
            .sum()
    }

    /// Empty columns with room for `n` rows (the caller bounds `n`: it comes from an untrusted
    /// file's indexes, and a schema may declare thousands of fields).
    pub(crate) fn columns_with_capacity(&self, n: usize) -> Vec<Column> {
        self.decodings
            .iter()
            .map(|d| match d.empty_column() {
                Column::F64(_) => Column::F64(Vec::with_capacity(n)),
                Column::U64(_) => Column::U64(Vec::with_capacity(n)),
                Column::Str(_) => Column::Str(Vec::with_capacity(n)),
            })
            .collect()
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
    /// A varint: one byte inline (the common case: keys, lengths, small numbers), longer ones
    /// out of line.
    #[inline]
    pub(crate) fn varint(&mut self) -> Result<u64, String> {
        if let Some(&b) = self.data.get(self.pos)
            && b < 0x80
        {
            self.pos += 1;
            return Ok(u64::from(b));
        }
        self.varint_long()
    }
    fn varint_long(&mut self) -> Result<u64, String> {
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
    /// Consumes the field key `key` if it comes next (true), else leaves the position (false).
    #[inline]
    pub(crate) fn expect_key(&mut self, key: u64) -> bool {
        if key < 0x80 {
            if self.data.get(self.pos) == Some(&(key as u8)) {
                self.pos += 1;
                return true;
            }
            return false;
        }
        let at = self.pos;
        if self.varint() == Ok(key) {
            return true;
        }
        self.pos = at;
        false
    }
    #[inline]
    pub(crate) fn key(&mut self) -> Result<(u32, u32), String> {
        let key = self.varint()?;
        let number = key >> 3;
        if number == 0 || number > u64::from(u32::MAX >> 3) {
            return Err(format!("a field number from 1 to 2^29-1, found {number}"));
        }
        Ok((number as u32, (key & 7) as u32))
    }
    #[inline]
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
    #[inline]
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
    /// Frame ids as bytes (the caller checks them as UTF-8).
    pub parent: &'a [u8],
    pub child: &'a [u8],
    pub translation: [f64; 3],
    pub rotation: [f64; 4],
}

fn decode_doubles<const N: usize>(data: &[u8], what: &str) -> Result<[f64; N], String> {
    let mut out = [0.0; N];
    // Fast path: every field once, in order (as our writer and most encoders write them).
    if data.len() == 9 * N
        && (0..N).all(|i| data[9 * i] as usize == ((i + 1) << 3) | WIRE_FIXED64 as usize)
    {
        for (i, v) in out.iter_mut().enumerate() {
            let mut a = [0u8; 8];
            a.copy_from_slice(&data[9 * i + 1..9 * i + 9]);
            *v = f64::from_le_bytes(a);
        }
        return Ok(out);
    }
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
        parent: b"",
        child: b"",
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
                let s = r.len_delimited()?;
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

#[cfg(test)]
#[allow(clippy::unwrap_used)]
mod tests {
    use super::*;
    use crate::schema::{FieldSpec, RecordSchema, put_varint};

    fn layout() -> RecordLayout {
        let schema = RecordSchema {
            full_name: "t.Row".into(),
            fields: vec![
                FieldSpec::f64("a", ""),
                FieldSpec::u64("b"),
                FieldSpec::str("c"),
                FieldSpec::f64("d", ""),
            ],
        };
        RecordLayout::from_descriptor_set(&schema.file_descriptor_set(), "t.Row").unwrap()
    }

    fn field(buf: &mut Vec<u8>, number: u64, v: &Column) {
        match v {
            Column::F64(x) => {
                put_varint(buf, (number << 3) | 1);
                buf.extend_from_slice(&x[0].to_le_bytes());
            }
            Column::U64(x) => {
                put_varint(buf, number << 3);
                put_varint(buf, x[0]);
            }
            Column::Str(x) => {
                put_varint(buf, (number << 3) | 2);
                put_varint(buf, x[0].len() as u64);
                buf.extend_from_slice(x[0].as_bytes());
            }
        }
    }

    /// The canonical fast path and the field-by-field decoder agree on every ordering, on
    /// missing, repeated and unknown fields, and a failed fast attempt leaves no partial row.
    #[test]
    fn decode_row_agrees_with_the_general_decoder() {
        let l = layout();
        let vals = [
            Column::F64(vec![-0.0]),
            Column::U64(vec![300]),
            Column::Str(vec!["héllo".into()]),
            Column::F64(vec![f64::from_bits(0x7ff8_0000_dead_beef)]),
        ];
        let enc = |order: &[usize]| {
            let mut b = Vec::new();
            for &i in order {
                field(&mut b, i as u64 + 1, &vals[i]);
            }
            b
        };
        let mut unknown = enc(&[0, 1, 2, 3]);
        unknown.extend_from_slice(&[0x48, 0x07]); // field 9, varint 7: not in the schema
        let mut repeated = enc(&[0, 1, 2, 3]);
        field(&mut repeated, 2, &Column::U64(vec![5]));
        let cases: Vec<Vec<u8>> = vec![
            enc(&[0, 1, 2, 3]),
            enc(&[3, 2, 1, 0]),
            enc(&[0, 2]),
            enc(&[]),
            unknown,
            repeated,
        ];
        let mut fast = l.columns_with_capacity(0);
        let mut slow = l.columns_with_capacity(0);
        for c in &cases {
            l.decode_row(c, &mut fast).unwrap();
            l.decode_into(c, &mut slow).unwrap();
        }
        let bits = |cols: &[Column]| -> Vec<String> {
            cols.iter()
                .map(|c| match c {
                    Column::F64(v) => {
                        format!("{:?}", v.iter().map(|x| x.to_bits()).collect::<Vec<_>>())
                    }
                    other => format!("{other:?}"),
                })
                .collect()
        };
        assert_eq!(bits(&fast), bits(&slow));
        assert_eq!(
            fast[1].as_u64().unwrap()[5],
            5,
            "the last of repeated fields wins"
        );
        assert_eq!(
            fast[3].as_f64().unwrap()[0].to_bits(),
            0x7ff8_0000_dead_beef
        );
        // A truncated canonical row is an error and leaves every column the same length.
        let full = enc(&[0, 1, 2, 3]);
        let before = fast.iter().map(Column::len).collect::<Vec<_>>();
        assert!(l.decode_row(&full[..full.len() - 3], &mut fast).is_err());
        let n = fast[0].len();
        assert!(fast.iter().all(|c| c.len() == n), "ragged columns");
        assert!(n <= before[0] + 1);
    }
}
