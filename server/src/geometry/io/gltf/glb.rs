//! The GLB container: a 12-byte header, a JSON chunk, and an optional binary chunk.

/// The chunks of a GLB file.
#[derive(Debug)]
pub(super) struct Glb<'a> {
    pub json: &'a [u8],
    pub bin: Option<&'a [u8]>,
}

/// The magic a GLB file begins with.
pub(super) const MAGIC: &[u8; 4] = b"glTF";
const HEADER: usize = 12;
const CHUNK_HEADER: usize = 8;

/// Splits a GLB file into its chunks; every length in it is checked against the bytes present.
pub(super) fn split(bytes: &[u8]) -> Result<Glb<'_>, String> {
    let word = |at: usize| u32::from_le_bytes(bytes[at..at + 4].try_into().expect("four bytes"));
    if bytes.len() < HEADER {
        return Err(format!(
            "truncated GLB file: {} bytes, fewer than its 12-byte header",
            bytes.len()
        ));
    }
    if &bytes[..4] != MAGIC {
        return Err("not a GLB file: its first bytes are not the magic \"glTF\"".to_owned());
    }
    if word(4) != 2 {
        return Err(format!("GLB version {}; vas reads version 2", word(4)));
    }
    if word(8) as usize != bytes.len() {
        return Err(format!(
            "the GLB header gives a length of {} bytes, but the file has {} (truncated, or \
             followed by other data)",
            word(8),
            bytes.len()
        ));
    }
    let mut at = HEADER;
    let mut json = None;
    let mut bin = None;
    while at < bytes.len() {
        if bytes.len() - at < CHUNK_HEADER {
            return Err(format!(
                "truncated GLB file: a chunk header at byte {at} is cut off"
            ));
        }
        let length = word(at) as usize;
        let kind = &bytes[at + 4..at + 8];
        let start = at + CHUNK_HEADER;
        if length > bytes.len() - start {
            return Err(format!(
                "truncated GLB file: the chunk at byte {at} claims {length} bytes, {} remain",
                bytes.len() - start
            ));
        }
        let data = &bytes[start..start + length];
        match kind {
            b"JSON" if json.is_none() && at == HEADER => json = Some(data),
            b"BIN\0" if json.is_some() && bin.is_none() => bin = Some(data),
            b"JSON" | b"BIN\0" => {
                return Err(format!("the GLB chunk at byte {at} is out of order"));
            }
            // Chunks of other types are for extensions, and are skipped (glTF 2.0, 4.4.3).
            _ => {}
        }
        at = start + length;
    }
    let json = json.ok_or("the GLB file has no JSON chunk")?;
    Ok(Glb { json, bin })
}
