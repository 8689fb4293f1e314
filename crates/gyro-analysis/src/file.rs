//! Files written whole or not at all: every table, plot and baseline this crate writes, and
//! every file gyro-study and the command line write, goes through [`write_whole`], so a
//! failure part-way (a full disk, a writer that refuses the frame) never leaves half a file
//! under the final name. (Recordings have their own `.partial` life in gyro-mcap; a saved
//! `.rrd` is renamed by gyro-view, as Rerun's sink writes the file itself.)

use std::fs::File;
use std::io::{BufWriter, Write};
use std::path::Path;

use crate::error::{AnalysisError, Result};

/// `fill` writes `<path>.partial` (the recorder's convention, [`gyro_mcap::partial_path`]),
/// which is renamed to `path` once `fill` returns Ok and the data are flushed. On any error
/// the partial file is removed and a file already at `path` is left as it was.
pub fn write_whole(
    path: &Path,
    fill: impl FnOnce(&mut BufWriter<File>) -> Result<()>,
) -> Result<()> {
    let tmp = gyro_mcap::partial_path(path);
    let result = File::create(&tmp)
        .map_err(AnalysisError::io(&tmp, "creating"))
        .and_then(|file| {
            let mut w = BufWriter::new(file);
            fill(&mut w)?;
            w.into_inner()
                .map_err(|e| AnalysisError::io(&tmp, "writing")(e.into_error()))?
                .sync_all()
                .map_err(AnalysisError::io(&tmp, "syncing"))
        })
        .and_then(|()| std::fs::rename(&tmp, path).map_err(AnalysisError::io(path, "renaming")));
    if result.is_err() {
        let _ = std::fs::remove_file(&tmp);
    }
    result
}

/// [`write_whole`] with bytes already in memory.
pub fn write_bytes(path: &Path, bytes: &[u8]) -> Result<()> {
    write_whole(path, |w| {
        w.write_all(bytes)
            .map_err(AnalysisError::io(path, "writing"))
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_failed_fill_leaves_the_old_file_and_no_partial() {
        let dir = std::env::temp_dir().join(format!("gyro-analysis-file-{}", std::process::id()));
        std::fs::create_dir_all(&dir).expect("dir");
        let path = dir.join("t.csv");
        write_whole(&path, |w| {
            w.write_all(b"old")
                .map_err(AnalysisError::io(&path, "writing"))
        })
        .expect("first write");
        let e = write_whole(&path, |w| {
            w.write_all(b"half of a new")
                .map_err(AnalysisError::io(&path, "writing"))?;
            Err(AnalysisError::Input {
                input: "t".into(),
                what: "refused part-way".into(),
            })
        })
        .expect_err("the fill fails");
        assert!(e.to_string().contains("refused part-way"), "{e}");
        assert_eq!(std::fs::read(&path).expect("read"), b"old");
        assert!(!gyro_mcap::partial_path(&path).exists());
        write_whole(&path, |w| {
            w.write_all(b"new")
                .map_err(AnalysisError::io(&path, "writing"))
        })
        .expect("second write");
        assert_eq!(std::fs::read(&path).expect("read"), b"new");
        let _ = std::fs::remove_dir_all(&dir);
    }
}
