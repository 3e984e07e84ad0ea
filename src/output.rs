//! Output helpers shared by the commands: atomic file writes and number formatting.

use std::io::Write;
use std::path::Path;

use crate::cli::CliError;

/// Writes `contents` to `path` atomically: the bytes go to a temporary file in the same
/// directory, which is then renamed over `path`, so a reader never sees a partial file.
/// On Unix the file is created with mode 0644 (less the umask), like an ordinary output file,
/// so run folders stay readable by collaborators on shared machines.
pub fn write_atomic(path: &Path, contents: &[u8]) -> Result<(), CliError> {
    let dir = match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d,
        _ => Path::new("."),
    };
    let mut builder = tempfile::Builder::new();
    #[cfg(unix)]
    {
        use std::os::unix::fs::PermissionsExt;
        builder.permissions(std::fs::Permissions::from_mode(0o644));
    }
    let mut tmp = builder
        .tempfile_in(dir)
        .map_err(|e| CliError::failure(format!("cannot write in {}: {e}", dir.display())))?;
    tmp.write_all(contents)
        .and_then(|()| tmp.as_file().sync_all())
        .map_err(|e| CliError::failure(format!("cannot write {}: {e}", path.display())))?;
    tmp.persist(path)
        .map_err(|e| CliError::failure(format!("cannot write {}: {}", path.display(), e.error)))?;
    Ok(())
}

/// Serialises `value` as pretty JSON followed by a newline.
pub fn to_json_line<T: serde::Serialize>(value: &T) -> Result<String, CliError> {
    let mut s = serde_json::to_string_pretty(value)
        .map_err(|e| CliError::failure(format!("cannot serialise output: {e}")))?;
    s.push('\n');
    Ok(s)
}
