//! What a channel carries: record schemas (flat proto3 messages of our own package) and poses
//! (`foxglove.FrameTransform`), with their FileDescriptorSets and hand-written protobuf encoders.

use prost::Message as _;
use prost_types::field_descriptor_proto::{Label, Type};
use prost_types::{DescriptorProto, FieldDescriptorProto, FileDescriptorProto, FileDescriptorSet};

/// The type of one record field, and so of its column when read back.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum FieldKind {
    /// protobuf `double` (wire type fixed64).
    F64,
    /// protobuf `uint64` (varint).
    U64,
    /// protobuf `string`.
    Str,
}

/// One field of a record: its name (a protobuf identifier), kind and unit (documentation only; it is
/// recorded in the channel's metadata as `unit.<name>`).
#[derive(Debug, Clone, PartialEq, Eq, Hash)]
pub struct FieldSpec {
    pub name: String,
    pub kind: FieldKind,
    pub unit: Option<String>,
}

impl FieldSpec {
    pub fn f64(name: &str, unit: &str) -> Self {
        Self {
            name: name.to_owned(),
            kind: FieldKind::F64,
            unit: (!unit.is_empty()).then(|| unit.to_owned()),
        }
    }
    pub fn u64(name: &str) -> Self {
        Self {
            name: name.to_owned(),
            kind: FieldKind::U64,
            unit: None,
        }
    }
    pub fn str(name: &str) -> Self {
        Self {
            name: name.to_owned(),
            kind: FieldKind::Str,
            unit: None,
        }
    }
}

/// A flat record type: becomes one proto3 message `full_name` (package = everything before the last
/// dot), fields numbered 1.. in order.
#[derive(Debug, Clone, PartialEq, Eq, Hash)]
pub struct RecordSchema {
    /// e.g. `gyrolab.CompassState`.
    pub full_name: String,
    pub fields: Vec<FieldSpec>,
}

/// One field value for [`crate::RecordingWriter::write_record`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Value<'a> {
    F64(f64),
    U64(u64),
    Str(&'a str),
}

/// The pose of `child_frame` in `parent_frame` (`parent_from_child`): translation in metres and a
/// unit quaternion (x, y, z, w).
#[derive(Debug, Clone, PartialEq)]
pub struct Pose {
    pub parent_frame: String,
    pub child_frame: String,
    pub translation_m: [f64; 3],
    pub rotation_xyzw: [f64; 4],
}

/// The MCAP schema name of pose channels.
pub(crate) const POSE_SCHEMA_NAME: &str = "foxglove.FrameTransform";

/// The encoded FileDescriptorSet of `foxglove.FrameTransform` with its imports
/// (foxglove/Vector3, foxglove/Quaternion, google/protobuf/timestamp), compiled from `proto/` at
/// build time.
pub(crate) const FRAME_TRANSFORM_FDS: &[u8] =
    include_bytes!(concat!(env!("OUT_DIR"), "/frame_transform.fds"));

fn is_identifier(s: &str) -> bool {
    let mut chars = s.chars();
    matches!(chars.next(), Some(c) if c.is_ascii_alphabetic() || c == '_')
        && chars.all(|c| c.is_ascii_alphanumeric() || c == '_')
}

/// Largest field count: protobuf reserves field numbers 19000..=19999.
pub(crate) const MAX_FIELDS: usize = 18_999;

impl RecordSchema {
    /// Checks names: a dotted full name of identifiers, unique identifier field names.
    pub(crate) fn validate(&self) -> Result<(), String> {
        if self.full_name.is_empty() || !self.full_name.split('.').all(is_identifier) {
            return Err(format!(
                "a dotted protobuf name such as \"gyrolab.CompassState\", found {:?}",
                self.full_name
            ));
        }
        if self.fields.len() > MAX_FIELDS {
            return Err(format!(
                "at most {MAX_FIELDS} fields, found {}",
                self.fields.len()
            ));
        }
        let mut seen = std::collections::HashSet::new();
        for f in &self.fields {
            if !is_identifier(&f.name) {
                return Err(format!(
                    "field names that are protobuf identifiers, found {:?}",
                    f.name
                ));
            }
            if !seen.insert(f.name.as_str()) {
                return Err(format!("unique field names, found {:?} twice", f.name));
            }
        }
        Ok(())
    }

    /// The package and the message's short name.
    pub(crate) fn split_name(&self) -> (&str, &str) {
        match self.full_name.rsplit_once('.') {
            Some((package, name)) => (package, name),
            None => ("", self.full_name.as_str()),
        }
    }

    /// The proto3 FileDescriptorSet (one file) that describes this record, encoded.
    pub(crate) fn file_descriptor_set(&self) -> Vec<u8> {
        let (package, name) = self.split_name();
        let field = self
            .fields
            .iter()
            .enumerate()
            .map(|(i, f)| FieldDescriptorProto {
                name: Some(f.name.clone()),
                number: Some(i as i32 + 1),
                label: Some(Label::Optional as i32),
                r#type: Some(match f.kind {
                    FieldKind::F64 => Type::Double,
                    FieldKind::U64 => Type::Uint64,
                    FieldKind::Str => Type::String,
                } as i32),
                json_name: Some(json_name(&f.name)),
                ..Default::default()
            })
            .collect();
        let file = FileDescriptorProto {
            name: Some(format!("{}.proto", self.full_name.replace('.', "/"))),
            package: (!package.is_empty()).then(|| package.to_owned()),
            message_type: vec![DescriptorProto {
                name: Some(name.to_owned()),
                field,
                ..Default::default()
            }],
            syntax: Some("proto3".to_owned()),
            ..Default::default()
        };
        FileDescriptorSet { file: vec![file] }.encode_to_vec()
    }
}

/// protoc's lowerCamelCase JSON name.
fn json_name(name: &str) -> String {
    let mut out = String::with_capacity(name.len());
    let mut upper = false;
    for c in name.chars() {
        if c == '_' {
            upper = true;
        } else if upper {
            out.push(c.to_ascii_uppercase());
            upper = false;
        } else {
            out.push(c);
        }
    }
    out
}

// ---------------------------------------------------------------------------------------------
// Protobuf wire encoding (hand-written: our messages are flat and the writer is hot)

pub(crate) const WIRE_VARINT: u32 = 0;
pub(crate) const WIRE_FIXED64: u32 = 1;
pub(crate) const WIRE_LEN: u32 = 2;
pub(crate) const WIRE_FIXED32: u32 = 5;

pub(crate) fn varint_len(v: u64) -> usize {
    // 1 + floor(log2(v)) / 7, with 0 → 1
    (64 - (v | 1).leading_zeros() as usize).div_ceil(7)
}

#[inline]
pub(crate) fn put_varint(buf: &mut Vec<u8>, mut v: u64) {
    while v >= 0x80 {
        buf.push((v as u8) | 0x80);
        v >>= 7;
    }
    buf.push(v as u8);
}

/// A field tag, pre-encoded.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Tag {
    bytes: [u8; 5],
    len: u8,
}

impl Tag {
    pub(crate) fn new(number: u32, wire: u32) -> Self {
        let mut v = Vec::with_capacity(5);
        put_varint(&mut v, u64::from((number << 3) | wire));
        let mut bytes = [0u8; 5];
        bytes[..v.len()].copy_from_slice(&v);
        Self {
            bytes,
            len: v.len() as u8,
        }
    }
    #[inline]
    pub(crate) fn as_slice(&self) -> &[u8] {
        &self.bytes[..self.len as usize]
    }
    pub(crate) fn len(&self) -> usize {
        self.len as usize
    }
}

/// The encoded length of a FrameTransform message (for the record length field).
#[inline]
pub(crate) fn pose_encoded_len(log_time_ns: u64, pose: &Pose) -> usize {
    let ts = timestamp_len(log_time_ns);
    let p = pose.parent_frame.len();
    let c = pose.child_frame.len();
    (1 + varint_len(ts as u64) + ts)
        + (1 + varint_len(p as u64) + p)
        + (1 + varint_len(c as u64) + c)
        + (2 + 27)
        + (2 + 36)
}

#[inline]
fn timestamp_len(log_time_ns: u64) -> usize {
    let (s, n) = split_ns(log_time_ns);
    1 + varint_len(s) + 1 + varint_len(n)
}

#[inline]
fn split_ns(t: u64) -> (u64, u64) {
    (t / 1_000_000_000, t % 1_000_000_000)
}

/// Sequential writes into a slice sized beforehand (no capacity checks per byte).
struct Cursor<'a> {
    out: &'a mut [u8],
    at: usize,
}

impl Cursor<'_> {
    #[inline]
    fn byte(&mut self, b: u8) {
        self.out[self.at] = b;
        self.at += 1;
    }
    #[inline]
    fn bytes(&mut self, b: &[u8]) {
        self.out[self.at..self.at + b.len()].copy_from_slice(b);
        self.at += b.len();
    }
    #[inline]
    fn varint(&mut self, mut v: u64) {
        while v >= 0x80 {
            self.byte((v as u8) | 0x80);
            v >>= 7;
        }
        self.byte(v as u8);
    }
    /// A Vector3 or Quaternion: every component written (zeros too), fields 1.. in order.
    #[inline]
    fn doubles<const N: usize>(&mut self, tag: u8, v: &[f64; N]) {
        let mut b = [0u8; 38];
        b[0] = tag;
        b[1] = (9 * N) as u8;
        for (i, x) in v.iter().enumerate() {
            b[2 + 9 * i] = (((i + 1) << 3) | 1) as u8;
            b[3 + 9 * i..11 + 9 * i].copy_from_slice(&x.to_le_bytes());
        }
        self.bytes(&b[..2 + 9 * N]);
    }
}

/// Encodes `foxglove.FrameTransform` into `out`, which is exactly [`pose_encoded_len`] bytes
/// long, with every field written (zeros too: dense, and so regular that zstd compresses it
/// faster and smaller than proto3's zero-less form).
pub(crate) fn encode_pose(out: &mut [u8], log_time_ns: u64, pose: &Pose) {
    let (s, n) = split_ns(log_time_ns);
    let mut c = Cursor { out, at: 0 };
    c.byte(0x0A); // 1: timestamp
    c.varint(timestamp_len(log_time_ns) as u64);
    c.byte(0x08);
    c.varint(s);
    c.byte(0x10);
    c.varint(n);
    c.byte(0x12); // 2: parent_frame_id
    c.varint(pose.parent_frame.len() as u64);
    c.bytes(pose.parent_frame.as_bytes());
    c.byte(0x1A); // 3: child_frame_id
    c.varint(pose.child_frame.len() as u64);
    c.bytes(pose.child_frame.as_bytes());
    c.doubles(0x22, &pose.translation_m); // 4: translation
    c.doubles(0x2A, &pose.rotation_xyzw); // 5: rotation
    debug_assert_eq!(c.at, c.out.len(), "pose_encoded_len and encode_pose agree");
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn varint_len_matches_encoding() {
        for v in [0, 1, 127, 128, 16383, 16384, u64::MAX / 2, u64::MAX] {
            let mut b = Vec::new();
            put_varint(&mut b, v);
            assert_eq!(b.len(), varint_len(v), "{v}");
        }
    }

    #[test]
    fn pose_len_matches_encoding() {
        let mut pose = Pose {
            parent_frame: "earth".into(),
            child_frame: "ship".repeat(40),
            translation_m: [1.0, 2.0, 3.0],
            rotation_xyzw: [0.0, 0.0, 0.0, 1.0],
        };
        for (tr, rot) in [
            ([1.0, 2.0, 3.0], [0.0, 0.0, 0.0, 1.0]),
            ([0.0; 3], [0.0; 4]),
            ([-0.0, f64::NAN, 0.0], [0.5, -0.5, 0.5, -0.5]),
        ] {
            pose.translation_m = tr;
            pose.rotation_xyzw = rot;
            for t in [0, 5, 999_999_999, 1_000_000_000, u64::MAX] {
                // Too short a buffer panics; too long leaves a zero byte that fails to decode.
                let mut b = vec![0u8; pose_encoded_len(t, &pose)];
                encode_pose(&mut b, t, &pose);
                let d = crate::decode::decode_pose(&b).expect("decodes");
                assert_eq!(d.child, pose.child_frame.as_bytes());
                for (a, b) in d.translation.iter().zip(&pose.translation_m) {
                    assert_eq!(a.to_bits(), b.to_bits());
                }
                for (a, b) in d.rotation.iter().zip(&pose.rotation_xyzw) {
                    assert_eq!(a.to_bits(), b.to_bits());
                }
            }
        }
    }

    #[test]
    fn frame_transform_descriptor_set_has_its_imports() {
        let fds = FileDescriptorSet::decode(FRAME_TRANSFORM_FDS).expect("valid descriptor set");
        let names: Vec<_> = fds.file.iter().filter_map(|f| f.name.clone()).collect();
        for want in [
            "google/protobuf/timestamp.proto",
            "foxglove/Vector3.proto",
            "foxglove/Quaternion.proto",
            "foxglove/FrameTransform.proto",
        ] {
            assert!(
                names.iter().any(|n| n == want),
                "{want} missing from {names:?}"
            );
        }
    }
}
