//! Merging: combines the shard folders of one sweep into a single sweep folder, after
//! checking that they are shards of the same sweep, that together they cover every shard,
//! and that every run in them is complete with a log `sepg audit` would read
//! ([`crate::logcheck::validate_log`]).

use std::fs;
use std::path::{Path, PathBuf};

use crate::error::{Error, Result};
use crate::folder::{check_out_dir, is_complete, to_json_line, write_atomic};
use crate::logcheck::validate_log;
use crate::sweep::{SWEEP_FILE, Shard, SweepFile};

fn copy_dir(from: &Path, to: &Path) -> Result<()> {
    let fail =
        |p: &Path, e: std::io::Error| Error::failed_from(format!("cannot copy {}", p.display()), e);
    fs::create_dir_all(to).map_err(|e| fail(to, e))?;
    for entry in fs::read_dir(from).map_err(|e| fail(from, e))? {
        let entry = entry.map_err(|e| fail(from, e))?;
        let src = entry.path();
        let dst = to.join(entry.file_name());
        if src.is_dir() {
            copy_dir(&src, &dst)?;
        } else {
            fs::copy(&src, &dst).map_err(|e| fail(&src, e))?;
        }
    }
    Ok(())
}

/// Checks the shards and returns the merged `sweep.json`.
///
/// # Errors
/// [`Error::Invalid`] when the folders are not complete shards of one sweep covering every
/// shard, or a run's log is not valid (naming the log file and its first bad line).
pub fn check_shards(shards: &[(PathBuf, SweepFile)]) -> Result<SweepFile> {
    let Some((first_dir, first)) = shards.first() else {
        return Err(Error::invalid("no shard folder given"));
    };
    let count = first.shard.count;
    let mut seen = vec![false; count];
    for (dir, f) in shards {
        if f.sweep_id != first.sweep_id || f.runs != first.runs {
            return Err(Error::invalid(format!(
                "{} and {} are not shards of the same sweep",
                first_dir.display(),
                dir.display()
            )));
        }
        if f.shard.count != count {
            return Err(Error::invalid(format!(
                "{} is shard {}/{} but {} is shard {}/{}",
                dir.display(),
                f.shard.index,
                f.shard.count,
                first_dir.display(),
                first.shard.index,
                count
            )));
        }
        if std::mem::replace(&mut seen[f.shard.index], true) {
            return Err(Error::invalid(format!(
                "shard {}/{count} is given twice",
                f.shard.index
            )));
        }
        if let Some(r) = f.shard_runs().find(|r| !is_complete(&dir.join(&r.dir))) {
            return Err(Error::invalid(format!(
                "run {} in {} is not complete (resume that shard first)",
                r.dir,
                dir.display()
            )));
        }
        for r in f.shard_runs() {
            validate_log(&dir.join(&r.dir))?.require_complete()?;
        }
    }
    let missing: Vec<String> = (0..count)
        .filter(|&i| !seen[i])
        .map(|i| format!("{i}/{count}"))
        .collect();
    if !missing.is_empty() {
        return Err(Error::invalid(format!(
            "missing shard(s) {}",
            missing.join(", ")
        )));
    }
    Ok(SweepFile {
        shard: Shard { index: 0, count: 1 },
        merged_from: shards.len(),
        ..first.clone()
    })
}

/// Merges the shard folders `shards` of one sweep into the sweep folder `out` and returns
/// its `sweep.json`. The output appears only once complete: it is assembled in a temporary
/// sibling folder and renamed.
///
/// # Errors
/// [`Error::Invalid`] for folders that are not complete shards of one sweep or a non-empty
/// output folder (without `force`, or one that is not a sweep folder); [`Error::Failed`] for
/// I/O errors.
pub fn merge(shards: &[PathBuf], out: &Path, force: bool) -> Result<SweepFile> {
    let shards = shards
        .iter()
        .map(|d| SweepFile::read(d).map(|f| (d.clone(), f)))
        .collect::<Result<Vec<_>>>()?;
    let merged = check_shards(&shards)?;
    check_out_dir(out, force, &[])?;
    let non_empty = fs::read_dir(out).is_ok_and(|mut d| d.next().is_some());
    if non_empty && !out.join(SWEEP_FILE).is_file() {
        return Err(Error::invalid(format!(
            "{} is not a sweep folder; --force only replaces a previous sweep",
            out.display()
        )));
    }
    let parent = match out.parent() {
        Some(p) if !p.as_os_str().is_empty() => p.to_path_buf(),
        _ => PathBuf::from("."),
    };
    fs::create_dir_all(&parent)
        .map_err(|e| Error::failed_from(format!("cannot create {}", parent.display()), e))?;
    let tmp = crate::folder::output_builder(0o755)
        .prefix(".sepg-merge-")
        .tempdir_in(&parent)
        .map_err(|e| Error::failed_from(format!("cannot write in {}", parent.display()), e))?;
    for (dir, f) in &shards {
        for r in f.shard_runs() {
            copy_dir(&dir.join(&r.dir), &tmp.path().join(&r.dir))?;
        }
    }
    write_atomic(
        &tmp.path().join(SWEEP_FILE),
        to_json_line(&merged)?.as_bytes(),
    )?;
    if out.exists() {
        fs::remove_dir_all(out)
            .map_err(|e| Error::failed_from(format!("cannot replace {}", out.display()), e))?;
    }
    let built = tmp.keep();
    fs::rename(&built, out)
        .map_err(|e| Error::failed_from(format!("cannot create {}", out.display()), e))?;
    crate::sweep::write_summary_csv(out, &merged, false)?;
    Ok(merged)
}
