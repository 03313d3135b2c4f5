//! A glTF file's buffers: the GLB binary chunk, `data:` URIs, and files beside the `.gltf`.
//!
//! A buffer file is named by a relative URI that must stay inside the `.gltf` file's folder (no
//! absolute path, no scheme, no `..`), must be a regular file, and counts towards the mesh-file
//! size limit together with the `.gltf` and the other buffers: a document cannot make vas read
//! files elsewhere, or more bytes than one mesh file may have.

use std::borrow::Cow;
use std::path::{Component, Path};

use base64::Engine as _;

use super::document::Document;
use crate::geometry::io::{FileLimits, read_regular_file};

/// The data of every buffer of `document`, in order. `bin` is a GLB file's binary chunk,
/// `path` the glTF file (its folder resolves buffer files) and `used` the bytes already read
/// (the glTF file's own).
pub(super) fn load<'a>(
    document: &Document,
    path: &Path,
    bin: Option<&'a [u8]>,
    limits: &FileLimits,
    mut used: u64,
) -> Result<Vec<Cow<'a, [u8]>>, String> {
    let folder = path.parent().unwrap_or(Path::new(""));
    let mut buffers = Vec::with_capacity(document.buffers.len());
    for (index, buffer) in document.buffers.iter().enumerate() {
        let data: Cow<'a, [u8]> = match (&buffer.uri, bin) {
            (None, Some(bin)) if index == 0 => Cow::Borrowed(bin),
            (None, _) => {
                return Err(format!(
                    "buffer {index} has no uri and is not a GLB file's first buffer"
                ));
            }
            (Some(uri), _) if uri.starts_with("data:") => {
                Cow::Owned(decode_data_uri(uri).map_err(|e| format!("buffer {index}: {e}"))?)
            }
            (Some(uri), _) => {
                let relative = relative_path(uri).map_err(|e| format!("buffer {index}: {e}"))?;
                let file = folder.join(relative);
                let left = limits.mesh_bytes.saturating_sub(used);
                let data = read_regular_file(&file, left).map_err(|e| {
                    format!(
                        "buffer {index}: cannot read {} ({e}; the glTF file and its buffers \
                         may have {} bytes in all)",
                        file.display(),
                        limits.mesh_bytes
                    )
                })?;
                used += data.len() as u64;
                Cow::Owned(data)
            }
        };
        if buffer.byte_length > data.len() as u64 {
            return Err(format!(
                "buffer {index} declares {} bytes, but its data has {}",
                buffer.byte_length,
                data.len()
            ));
        }
        buffers.push(data);
    }
    Ok(buffers)
}

/// The bytes of a base64 `data:` URI.
fn decode_data_uri(uri: &str) -> Result<Vec<u8>, String> {
    let (header, data) = uri
        .split_once(',')
        .ok_or("a data: URI without a comma before its data")?;
    if !header.ends_with(";base64") {
        return Err("a data: URI that is not base64; only base64 data URIs are read".to_owned());
    }
    let engine = base64::engine::GeneralPurpose::new(
        &base64::alphabet::STANDARD,
        base64::engine::GeneralPurposeConfig::new()
            .with_decode_padding_mode(base64::engine::DecodePaddingMode::Indifferent),
    );
    engine
        .decode(data)
        .map_err(|e| format!("its data: URI is not valid base64 ({e})"))
}

/// The relative path a buffer URI names: percent-decoded, and refused if it is absolute, has a
/// scheme, or climbs out of the folder with `..`.
fn relative_path(uri: &str) -> Result<String, String> {
    let path = percent_decoded(uri).ok_or_else(|| format!("the URI {uri:?} is malformed"))?;
    let scheme = path
        .find(':')
        .is_some_and(|colon| !path[..colon].contains('/'));
    let escapes = Path::new(&path)
        .components()
        .any(|c| !matches!(c, Component::Normal(_) | Component::CurDir));
    if path.is_empty() || scheme || escapes {
        return Err(format!(
            "the URI {uri:?} is not a relative path inside the glTF file's folder (or a data: \
             URI)"
        ));
    }
    Ok(path)
}

/// `uri` with `%XX` escapes replaced by their bytes; `None` if an escape is malformed or the
/// result is not UTF-8.
fn percent_decoded(uri: &str) -> Option<String> {
    let bytes = uri.as_bytes();
    let mut decoded = Vec::with_capacity(bytes.len());
    let mut i = 0;
    while i < bytes.len() {
        if bytes[i] == b'%' {
            let hex = std::str::from_utf8(bytes.get(i + 1..i + 3)?).ok()?;
            decoded.push(u8::from_str_radix(hex, 16).ok()?);
            i += 3;
        } else {
            decoded.push(bytes[i]);
            i += 1;
        }
    }
    String::from_utf8(decoded).ok()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn uris_must_stay_in_the_folder() {
        assert_eq!(relative_path("parts%20one.bin").unwrap(), "parts one.bin");
        assert_eq!(relative_path("./data/a.bin").unwrap(), "./data/a.bin");
        for bad in [
            "../secret.bin",
            "data/../../secret.bin",
            "/etc/passwd",
            "file:///etc/passwd",
            "http://host/a.bin",
            "%2e%2e/secret.bin",
            "",
            "a%zz.bin",
        ] {
            assert!(relative_path(bad).is_err(), "{bad}");
        }
    }

    #[test]
    fn data_uris_decode_with_or_without_padding() {
        let uri = "data:application/octet-stream;base64,AQID";
        assert_eq!(decode_data_uri(uri).unwrap(), [1, 2, 3]);
        assert_eq!(decode_data_uri("data:;base64,AQI").unwrap(), [1, 2]);
        assert!(decode_data_uri("data:text/plain,hello").is_err());
        assert!(decode_data_uri("data:;base64,!!!").is_err());
    }
}
