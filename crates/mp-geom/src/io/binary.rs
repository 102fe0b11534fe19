//! The project's compact binary framing, shared by tracks (`.mpt`, see
//! [`super::native`]) and concrete programs (`.mpb`, in `mp-concrete`).
//!
//! Layout: a magic byte string naming the content (`mp-track`,
//! `mp-program`), a format version as a little-endian `u32`, then the
//! [bincode](https://docs.rs/bincode/2) 2 encoding of a record in bincode's
//! standard configuration: little-endian, integers and lengths as
//! variable-length integers, `f64` as 8 little-endian bytes, enum variants by
//! index. The record types are private to each format and mirror its public
//! type field by field.
//!
//! Decoding never trusts the bytes: a wrong magic, a newer version, a length
//! running past the end, an unknown enum variant, invalid UTF-8 or trailing
//! bytes are each a [`GeomError::Format`] naming the source, and the callers
//! validate the decoded record (shapes, finiteness) before building their
//! type. Declared lengths cannot make the decoder reserve more than
//! [`DECODE_LIMIT`] bytes for strings.

use std::path::Path;

use serde::de::DeserializeOwned;
use serde::Serialize;

use crate::error::{GeomError, Result};

/// Upper bound on the bytes the decoder may reserve for strings declared
/// in one input (a corrupt length field cannot ask for more).
pub const DECODE_LIMIT: usize = 1 << 28;

fn config() -> bincode::config::Configuration {
    bincode::config::standard()
}

/// Encodes `value` behind `magic` and `version`.
pub fn encode<T: Serialize>(magic: &[u8], version: u32, value: &T) -> Result<Vec<u8>> {
    let mut out = Vec::with_capacity(magic.len() + 4 + 256);
    out.extend_from_slice(magic);
    out.extend_from_slice(&version.to_le_bytes());
    let body = bincode::serde::encode_to_vec(value, config()).map_err(|e| {
        GeomError::format(
            String::from_utf8_lossy(magic).into_owned(),
            format!("cannot encode: {e}"),
        )
    })?;
    out.extend_from_slice(&body);
    Ok(out)
}

/// Decodes a record written by [`encode`] with the same `magic`; versions
/// from 1 up to `version` are accepted. `source` names the input in errors
/// (a file path, or a description such as `bincode track`).
pub fn decode<T: DeserializeOwned>(
    magic: &[u8],
    version: u32,
    bytes: &[u8],
    source: &Path,
) -> Result<T> {
    let name = String::from_utf8_lossy(magic);
    let err = |reason: String| GeomError::format(source, reason);
    if !bytes.starts_with(magic) {
        return Err(err(format!(
            "not an {name} binary: the data does not start with `{name}`"
        )));
    }
    let rest = &bytes[magic.len()..];
    let Some((v, body)) = rest.split_first_chunk::<4>() else {
        return Err(err(format!(
            "truncated {name} binary: {} bytes, the header needs {}",
            bytes.len(),
            magic.len() + 4
        )));
    };
    let v = u32::from_le_bytes(*v);
    if v == 0 || v > version {
        return Err(err(format!(
            "{name} binary format version {v} is not supported (this build reads 1 to {version})"
        )));
    }
    let (value, used): (T, usize) =
        bincode::serde::decode_from_slice(body, config().with_limit::<DECODE_LIMIT>())
            .map_err(|e| err(describe(&e, &name)))?;
    if used != body.len() {
        return Err(err(format!(
            "{} bytes after the end of the {name} record",
            body.len() - used
        )));
    }
    Ok(value)
}

fn describe(e: &bincode::error::DecodeError, name: &str) -> String {
    use bincode::error::DecodeError as D;
    match e {
        D::UnexpectedEnd { additional } => {
            format!("truncated {name} binary: the data ends {additional} or more bytes early")
        }
        D::LimitExceeded => {
            format!("corrupt {name} binary: a length field asks for more than {DECODE_LIMIT} bytes")
        }
        D::Utf8 { .. } => format!("corrupt {name} binary: a name is not valid UTF-8"),
        D::UnexpectedVariant { found, .. } => {
            format!("corrupt {name} binary: unknown variant {found}")
        }
        D::OutsideUsizeRange(v) => {
            format!("corrupt {name} binary: length or index {v} does not fit this machine")
        }
        other => format!("corrupt {name} binary: {other}"),
    }
}
