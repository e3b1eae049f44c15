//! Files read whole as text (robot, scenario, task, split, mapping and URDF files, a
//! summary, `identified.json`, `task.json`, a shard's `shard.json`, a checkpoint), each read
//! through [`read_bounded`]: no more than [`TEXT_CAP_MIB`] MiB, so that a stream without end
//! (`/dev/zero`) given for one is refused at once rather than filling the memory.

use std::io::Read;
use std::path::Path;

use super::{Error, Result};

/// The most a text file calbench reads whole may hold, in MiB: far above any real one (the
/// largest committed summary is under 2 MiB; a robot or scenario file a few kB).
pub const TEXT_CAP_MIB: u64 = 256;

/// The bytes of the file `path`, refused (an I/O error of kind `InvalidData`: `longer than
/// 256 MiB: …`) when it holds more than [`TEXT_CAP_MIB`] MiB, which is read no further.
pub fn read_bounded(path: &Path) -> std::io::Result<Vec<u8>> {
    let cap = TEXT_CAP_MIB << 20;
    let mut bytes = Vec::new();
    std::fs::File::open(path)?
        .take(cap + 1)
        .read_to_end(&mut bytes)?;
    if bytes.len() as u64 > cap {
        return Err(std::io::Error::new(
            std::io::ErrorKind::InvalidData,
            format!(
                "longer than {TEXT_CAP_MIB} MiB: not a robot, scenario, task, mapping or \
                 results file"
            ),
        ));
    }
    Ok(bytes)
}

/// [`read_bounded`] as UTF-8 text without a leading byte-order mark (as [`read_text`]), for a
/// reader that words its own refusal of the file (a shard's `shard.json`, a checkpoint): text
/// that is not UTF-8 is an I/O error too.
pub fn read_bounded_text(path: &Path) -> std::io::Result<String> {
    let text = String::from_utf8(read_bounded(path)?).map_err(std::io::Error::other)?;
    Ok(without_bom(text))
}

/// `text` without a leading byte-order mark (an editor's UTF-8), which is not part of it.
fn without_bom(mut text: String) -> String {
    if text.starts_with('\u{feff}') {
        text.drain(..'\u{feff}'.len_utf8());
    }
    text
}

/// The text of the file `path`, every byte of it ([`read_text`] less a byte-order mark), for a
/// reader that writes the text back whole (a URDF). A file that cannot be read is refused with
/// the system's reason, one longer than [`TEXT_CAP_MIB`] MiB as such ([`read_bounded`]), and
/// one that is not UTF-8 (a Latin-1 `°`, a UTF-16 export) naming the line and the byte of the
/// first that is not, where the standard library's message named neither.
pub fn read_text_whole(path: &Path) -> Result<String> {
    let bytes = read_bounded(path).map_err(|e| Error::io(path, e))?;
    String::from_utf8(bytes).map_err(|e| {
        let good = e.utf8_error().valid_up_to();
        let bytes = e.as_bytes();
        let start = bytes[..good]
            .iter()
            .rposition(|&b| b == b'\n')
            .map_or(0, |i| i + 1);
        let line = bytes[..start].iter().filter(|&&b| b == b'\n').count() + 1;
        let msg = format!(
            "not UTF-8 text: byte {} of the line is 0x{:02X}; save the file as UTF-8",
            good - start + 1,
            bytes[good]
        );
        Error::file(path, format!("line {line}"), msg)
    })
}

/// The text of the file `path` ([`read_text_whole`]) without a leading byte-order mark (an
/// editor's UTF-8), which is not part of the text: a JSON file saved with one reads as
/// without, as TOML, CSV and URDF files do.
pub fn read_text(path: &Path) -> Result<String> {
    read_text_whole(path).map(without_bom)
}
