//! Output helpers shared by the commands: atomic file writes and JSON output.

use std::path::Path;

use crate::cli::CliError;

/// Writes `contents` to `path` atomically (see [`sepg_runs::folder::write_atomic`]).
pub fn write_atomic(path: &Path, contents: &[u8]) -> Result<(), CliError> {
    Ok(sepg_runs::folder::write_atomic(path, contents)?)
}

/// Serialises `value` as pretty JSON followed by a newline.
pub fn to_json_line<T: serde::Serialize>(value: &T) -> Result<String, CliError> {
    Ok(sepg_runs::folder::to_json_line(value)?)
}
