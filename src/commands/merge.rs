//! `sepg merge`: combines the shard folders of one sweep into a single sweep folder, after
//! checking that they are shards of the same sweep, that together they cover every shard,
//! and that every run in them is complete.

use std::fs;
use std::path::{Path, PathBuf};

use clap::Args;

use crate::cli::CliError;
use crate::commands::runfmt;
use crate::commands::sweep::{SWEEP_FILE, Shard, SweepFile};
use crate::output::{to_json_line, write_atomic};

/// Arguments of `sepg merge`.
#[derive(Debug, Args)]
pub struct MergeArgs {
    /// The shard folders written by `sepg sweep --shard I/N`.
    #[arg(required = true, value_name = "DIR")]
    shards: Vec<PathBuf>,
    /// Output sweep folder (must be absent or empty unless --force).
    #[arg(long, value_name = "DIR")]
    out: PathBuf,
    /// Replace a previous merge in a non-empty folder.
    #[arg(long)]
    force: bool,
    /// No summary line.
    #[arg(long)]
    quiet: bool,
}

fn copy_dir(from: &Path, to: &Path) -> Result<(), CliError> {
    let fail = |p: &Path, e: std::io::Error| {
        CliError::failure(format!("cannot copy {}: {e}", p.display()))
    };
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
/// Usage error when the folders are not complete shards of one sweep covering every shard.
pub fn check_shards(shards: &[(PathBuf, SweepFile)]) -> Result<SweepFile, CliError> {
    let (first_dir, first) = &shards[0];
    let count = first.shard.count;
    let mut seen = vec![false; count];
    for (dir, f) in shards {
        if f.sweep_id != first.sweep_id || f.runs != first.runs {
            return Err(CliError::usage(format!(
                "{} and {} are not shards of the same sweep",
                first_dir.display(),
                dir.display()
            )));
        }
        if f.shard.count != count {
            return Err(CliError::usage(format!(
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
            return Err(CliError::usage(format!(
                "shard {}/{count} is given twice",
                f.shard.index
            )));
        }
        if let Some(r) = f
            .shard_runs()
            .find(|r| !runfmt::is_complete(&dir.join(&r.dir)))
        {
            return Err(CliError::usage(format!(
                "run {} in {} is not complete (resume that shard first)",
                r.dir,
                dir.display()
            )));
        }
    }
    let missing: Vec<String> = (0..count)
        .filter(|&i| !seen[i])
        .map(|i| format!("{i}/{count}"))
        .collect();
    if !missing.is_empty() {
        return Err(CliError::usage(format!(
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

/// Runs `sepg merge`.
///
/// # Errors
/// Usage error (exit 2) for folders that are not complete shards of one sweep or a non-empty
/// output folder; failure (exit 1) for I/O errors. The output appears only once complete: it
/// is assembled in a temporary sibling folder and renamed.
pub fn run(args: &MergeArgs) -> Result<(), CliError> {
    let shards = args
        .shards
        .iter()
        .map(|d| SweepFile::read(d).map(|f| (d.clone(), f)))
        .collect::<Result<Vec<_>, _>>()?;
    let merged = check_shards(&shards)?;
    runfmt::check_out_dir(&args.out, args.force, &[])?;
    let non_empty = fs::read_dir(&args.out).is_ok_and(|mut d| d.next().is_some());
    if non_empty && !args.out.join(SWEEP_FILE).is_file() {
        return Err(CliError::usage(format!(
            "{} is not a sweep folder; --force only replaces a previous sweep",
            args.out.display()
        )));
    }
    let parent = match args.out.parent() {
        Some(p) if !p.as_os_str().is_empty() => p.to_path_buf(),
        _ => PathBuf::from("."),
    };
    fs::create_dir_all(&parent)
        .map_err(|e| CliError::failure(format!("cannot create {}: {e}", parent.display())))?;
    let tmp = tempfile::Builder::new()
        .prefix(".sepg-merge-")
        .tempdir_in(&parent)
        .map_err(|e| CliError::failure(format!("cannot write in {}: {e}", parent.display())))?;
    for (dir, f) in &shards {
        for r in f.shard_runs() {
            copy_dir(&dir.join(&r.dir), &tmp.path().join(&r.dir))?;
        }
    }
    write_atomic(
        &tmp.path().join(SWEEP_FILE),
        to_json_line(&merged)?.as_bytes(),
    )?;
    if args.out.exists() {
        fs::remove_dir_all(&args.out).map_err(|e| {
            CliError::failure(format!("cannot replace {}: {e}", args.out.display()))
        })?;
    }
    let built = tmp.keep();
    fs::rename(&built, &args.out)
        .map_err(|e| CliError::failure(format!("cannot create {}: {e}", args.out.display())))?;
    if !args.quiet {
        println!(
            "{}: {} runs from {} shards of sweep {}",
            args.out.display(),
            merged.runs.len(),
            shards.len(),
            merged.sweep_id
        );
    }
    Ok(())
}
