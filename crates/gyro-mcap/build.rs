//! Compiles the shipped foxglove schemas (and google/protobuf/timestamp.proto, which protox
//! carries) into one encoded FileDescriptorSet, the MCAP schema of pose channels.

use std::path::PathBuf;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let manifest_dir = PathBuf::from(std::env::var("CARGO_MANIFEST_DIR")?);
    let proto_dir = manifest_dir.join("proto");
    println!("cargo:rerun-if-changed=proto");
    let mut compiler = protox::Compiler::new([&proto_dir])?;
    compiler
        .include_source_info(false)
        .include_imports(true)
        .open_file(proto_dir.join("foxglove/FrameTransform.proto"))?;
    let bytes = compiler.encode_file_descriptor_set();
    let out_dir = PathBuf::from(std::env::var("OUT_DIR")?);
    std::fs::write(out_dir.join("frame_transform.fds"), bytes)?;
    Ok(())
}
