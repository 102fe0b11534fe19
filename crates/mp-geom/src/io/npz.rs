//! Reading `.npy` and `.npz` files of any numeric, boolean or unicode dtype.
//!
//! `ndarray-npy` reads one element type per call and cannot read numpy
//! unicode string arrays (`<U15`), which the shared data sets use for clip
//! names and action labels. This module reads the header with
//! `ndarray_npy::npy::header::Header`, keeps the raw bytes, and converts on
//! demand: every numeric or boolean dtype to `f64` ([`NpyArray::to_f64`]),
//! integer and boolean dtypes to `i64` ([`NpyArray::to_i64`]), and `<U`/`|S`
//! arrays to strings ([`NpyArray::to_strings`]).
//!
//! Both stored (`numpy.savez`) and deflate-compressed (`numpy.savez_compressed`)
//! archives are read. Writing goes through [`NpzOut`], which uses
//! `ndarray-npy` for numeric arrays and writes `<U` arrays itself.

use std::fmt;
use std::io::{Cursor, Read, Seek, Write};
use std::path::{Path, PathBuf};
use std::sync::Arc;

use ndarray::{ArrayD, IxDyn, ShapeBuilder};
use ndarray_npy::npy::header::{Header, Layout};
use ndarray_npy::WriteNpyExt;

use crate::error::{GeomError, Result};

/// Element type of an `.npy` array.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[non_exhaustive]
pub enum DType {
    /// Boolean (`|b1`).
    Bool,
    /// Signed integer of the given byte width (1, 2, 4, 8).
    Int(u8),
    /// Unsigned integer of the given byte width (1, 2, 4, 8).
    UInt(u8),
    /// IEEE float of the given byte width (4, 8).
    Float(u8),
    /// Unicode string of `n` UTF-32 code units (`<U{n}`).
    Unicode(usize),
    /// Byte string of `n` bytes (`|S{n}`).
    Bytes(usize),
}

impl DType {
    /// Size of one element in bytes.
    pub fn item_size(&self) -> usize {
        match *self {
            DType::Bool => 1,
            DType::Int(w) | DType::UInt(w) | DType::Float(w) => w as usize,
            DType::Unicode(n) => 4 * n,
            DType::Bytes(n) => n,
        }
    }

    /// Whether values of this type convert to numbers.
    pub fn is_numeric(&self) -> bool {
        !matches!(self, DType::Unicode(_) | DType::Bytes(_))
    }
}

impl fmt::Display for DType {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match *self {
            DType::Bool => write!(f, "|b1"),
            DType::Int(w) => write!(f, "<i{w}"),
            DType::UInt(w) => write!(f, "<u{w}"),
            DType::Float(w) => write!(f, "<f{w}"),
            DType::Unicode(n) => write!(f, "<U{n}"),
            DType::Bytes(n) => write!(f, "|S{n}"),
        }
    }
}

/// Parses a numpy type descriptor such as `<f4`, `|u1`, `<U15`.
/// Returns the type and whether it is big-endian.
fn parse_descr(descr: &str) -> Option<(DType, bool)> {
    let mut chars = descr.chars();
    let first = chars.next()?;
    let (order, rest) = match first {
        '<' | '>' | '|' | '=' => (first, &descr[1..]),
        _ => ('=', descr),
    };
    let big = match order {
        '>' => true,
        '=' => cfg!(target_endian = "big"),
        _ => false,
    };
    let kind = rest.chars().next()?;
    let num = &rest[kind.len_utf8()..];
    let n: usize = if num.is_empty() && kind == '?' {
        1
    } else {
        num.parse().ok()?
    };
    let dtype = match kind {
        'b' if n == 1 => DType::Bool,
        '?' => DType::Bool,
        'i' if matches!(n, 1 | 2 | 4 | 8) => DType::Int(n as u8),
        'u' if matches!(n, 1 | 2 | 4 | 8) => DType::UInt(n as u8),
        'f' if matches!(n, 4 | 8) => DType::Float(n as u8),
        'U' => DType::Unicode(n),
        'S' | 'a' => DType::Bytes(n),
        _ => return None,
    };
    Some((dtype, big))
}

/// Deepest bracket nesting of a supported `.npy` header: the dict, the shape tuple.
const MAX_HEADER_NESTING: usize = 2;

/// Refuses headers whose brackets nest deeper than a plain array's (the
/// header parser takes exponential time on deeply nested or unclosed
/// brackets). Bytes too short to hold a header are left to the parser.
fn check_header_nesting(bytes: &[u8], source: &str) -> Result<()> {
    if bytes.len() < 10 || !bytes.starts_with(b"\x93NUMPY") {
        return Ok(());
    }
    let (len, start) = if bytes[6] == 1 {
        (
            usize::from(u16::from_le_bytes([bytes[8], bytes[9]])),
            10usize,
        )
    } else if bytes.len() >= 12 {
        let l = u32::from_le_bytes([bytes[8], bytes[9], bytes[10], bytes[11]]);
        (usize::try_from(l).unwrap_or(usize::MAX), 12)
    } else {
        return Ok(());
    };
    let header = &bytes[start..bytes.len().min(start.saturating_add(len))];
    let mut depth = 0usize;
    for &b in header {
        match b {
            b'(' | b'[' | b'{' => {
                depth += 1;
                if depth > MAX_HEADER_NESTING {
                    return Err(GeomError::format(
                        source,
                        "not a valid .npy header: brackets nest deeper than a dict holding \
                         a shape (structured dtypes are not supported)",
                    ));
                }
            }
            b')' | b']' | b'}' => depth = depth.saturating_sub(1),
            _ => {}
        }
    }
    Ok(())
}

/// One array read from an `.npy` file (or an `.npz` member), not yet
/// converted: dtype, shape and the raw element bytes in file order.
#[derive(Debug, Clone)]
pub struct NpyArray {
    /// Where the array came from (file, or `file:member` for npz), for messages.
    pub source: String,
    /// Element type.
    pub dtype: DType,
    /// Shape (empty for a scalar).
    pub shape: Vec<usize>,
    /// Whether the data are stored in Fortran (column-major) order.
    pub fortran_order: bool,
    big_endian: bool,
    data: Vec<u8>,
}

impl NpyArray {
    /// Parses `.npy` bytes. `source` names the file in error messages.
    pub fn from_bytes(bytes: &[u8], source: &str) -> Result<Self> {
        check_header_nesting(bytes, source)?;
        let mut cur = Cursor::new(bytes);
        let header = Header::from_reader(&mut cur)
            .map_err(|e| GeomError::format(source, format!("not a valid .npy header: {e}")))?;
        let descr = header.type_descriptor.as_string().ok_or_else(|| {
            GeomError::format(
                source,
                format!(
                    "unsupported dtype {} (structured arrays are not supported)",
                    header.type_descriptor
                ),
            )
        })?;
        let (dtype, big_endian) = parse_descr(descr).ok_or_else(|| {
            GeomError::format(
                source,
                format!(
                    "unsupported dtype `{descr}` (supported: bool, int/uint 1-8 bytes, \
                     float32/64, <U unicode, |S bytes)"
                ),
            )
        })?;
        let count = header
            .shape
            .iter()
            .try_fold(1usize, |acc, &n| acc.checked_mul(n))
            .ok_or_else(|| GeomError::format(source, "array shape overflows"))?;
        let nbytes = count
            .checked_mul(dtype.item_size())
            .ok_or_else(|| GeomError::format(source, "array size overflows"))?;
        let start = cur.position() as usize;
        let avail = bytes.len().saturating_sub(start);
        if avail < nbytes {
            return Err(GeomError::format(
                source,
                format!(
                    "truncated array data: shape {:?} of {dtype} needs {nbytes} bytes, file has {avail}",
                    header.shape
                ),
            ));
        }
        Ok(NpyArray {
            source: source.to_string(),
            dtype,
            shape: header.shape.clone(),
            fortran_order: matches!(header.layout, Layout::Fortran),
            big_endian,
            data: bytes[start..start + nbytes].to_vec(),
        })
    }

    /// Number of elements.
    pub fn len(&self) -> usize {
        self.shape.iter().product()
    }

    /// True when the array has no elements.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    fn word<const N: usize>(&self, i: usize) -> [u8; N] {
        let mut b = [0u8; N];
        b.copy_from_slice(&self.data[i * N..(i + 1) * N]);
        if self.big_endian {
            b.reverse();
        }
        b
    }

    fn shaped<T: Clone>(&self, flat: Vec<T>) -> Result<ArrayD<T>> {
        let shape = IxDyn(&self.shape);
        let arr = if self.fortran_order {
            ArrayD::from_shape_vec(shape.f(), flat)
        } else {
            ArrayD::from_shape_vec(shape, flat)
        }
        .map_err(|e| GeomError::format(&self.source, format!("bad shape: {e}")))?;
        Ok(if self.fortran_order {
            arr.as_standard_layout().into_owned()
        } else {
            arr
        })
    }

    /// All elements as `f64` (standard layout), from any numeric or boolean dtype.
    pub fn to_f64(&self) -> Result<ArrayD<f64>> {
        let n = self.len();
        let flat: Vec<f64> = match self.dtype {
            DType::Bool => self
                .data
                .iter()
                .map(|&b| f64::from(u8::from(b != 0)))
                .collect(),
            DType::Int(1) => self.data.iter().map(|&b| f64::from(b as i8)).collect(),
            DType::UInt(1) => self.data.iter().map(|&b| f64::from(b)).collect(),
            DType::Int(2) => (0..n)
                .map(|i| f64::from(i16::from_le_bytes(self.word(i))))
                .collect(),
            DType::UInt(2) => (0..n)
                .map(|i| f64::from(u16::from_le_bytes(self.word(i))))
                .collect(),
            DType::Int(4) => (0..n)
                .map(|i| f64::from(i32::from_le_bytes(self.word(i))))
                .collect(),
            DType::UInt(4) => (0..n)
                .map(|i| f64::from(u32::from_le_bytes(self.word(i))))
                .collect(),
            DType::Int(8) => (0..n)
                .map(|i| i64::from_le_bytes(self.word(i)) as f64)
                .collect(),
            DType::UInt(8) => (0..n)
                .map(|i| u64::from_le_bytes(self.word(i)) as f64)
                .collect(),
            DType::Float(4) => (0..n)
                .map(|i| f64::from(f32::from_le_bytes(self.word(i))))
                .collect(),
            DType::Float(8) => (0..n).map(|i| f64::from_le_bytes(self.word(i))).collect(),
            other => {
                return Err(GeomError::format(
                    &self.source,
                    format!("dtype {other} cannot be read as numbers"),
                ))
            }
        };
        self.shaped(flat)
    }

    /// All elements as `i64`, from integer or boolean dtypes (floats are refused:
    /// use [`NpyArray::to_f64`]).
    pub fn to_i64(&self) -> Result<ArrayD<i64>> {
        let n = self.len();
        let flat: Vec<i64> = match self.dtype {
            DType::Bool => self.data.iter().map(|&b| i64::from(b != 0)).collect(),
            DType::Int(1) => self.data.iter().map(|&b| i64::from(b as i8)).collect(),
            DType::UInt(1) => self.data.iter().map(|&b| i64::from(b)).collect(),
            DType::Int(2) => (0..n)
                .map(|i| i64::from(i16::from_le_bytes(self.word(i))))
                .collect(),
            DType::UInt(2) => (0..n)
                .map(|i| i64::from(u16::from_le_bytes(self.word(i))))
                .collect(),
            DType::Int(4) => (0..n)
                .map(|i| i64::from(i32::from_le_bytes(self.word(i))))
                .collect(),
            DType::UInt(4) => (0..n)
                .map(|i| i64::from(u32::from_le_bytes(self.word(i))))
                .collect(),
            DType::Int(8) => (0..n).map(|i| i64::from_le_bytes(self.word(i))).collect(),
            DType::UInt(8) => (0..n)
                .map(|i| {
                    let v = u64::from_le_bytes(self.word(i));
                    i64::try_from(v).map_err(|_| {
                        GeomError::format(
                            &self.source,
                            format!("element {i} = {v} does not fit in i64"),
                        )
                    })
                })
                .collect::<Result<_>>()?,
            other => {
                return Err(GeomError::format(
                    &self.source,
                    format!("dtype {other} is not an integer type"),
                ))
            }
        };
        self.shaped(flat)
    }

    /// All elements as strings (flattened in standard order), from `<U` or `|S` dtypes.
    /// Trailing NUL padding is removed, as numpy does.
    pub fn to_strings(&self) -> Result<Vec<String>> {
        let (width, unicode) = match self.dtype {
            DType::Unicode(n) => (n, true),
            DType::Bytes(n) => (n, false),
            other => {
                return Err(GeomError::format(
                    &self.source,
                    format!("dtype {other} is not a string type"),
                ))
            }
        };
        let n = self.len();
        let mut flat = Vec::with_capacity(n);
        for i in 0..n {
            let s = if unicode {
                let mut s = String::with_capacity(width);
                for k in 0..width {
                    let off = (i * width + k) * 4;
                    let mut b = [0u8; 4];
                    b.copy_from_slice(&self.data[off..off + 4]);
                    let code = if self.big_endian {
                        u32::from_be_bytes(b)
                    } else {
                        u32::from_le_bytes(b)
                    };
                    if code == 0 {
                        break;
                    }
                    let c = char::from_u32(code).ok_or_else(|| {
                        GeomError::format(
                            &self.source,
                            format!("element {i}: invalid unicode code point {code:#x}"),
                        )
                    })?;
                    s.push(c);
                }
                s
            } else {
                let raw = &self.data[i * width..(i + 1) * width];
                let end = raw.iter().position(|&b| b == 0).unwrap_or(width);
                String::from_utf8_lossy(&raw[..end]).into_owned()
            };
            flat.push(s);
        }
        if self.fortran_order && self.shape.len() > 1 {
            let idx = self.shaped((0..n).collect::<Vec<usize>>())?;
            return Ok(idx.iter().map(|&i| flat[i].clone()).collect());
        }
        Ok(flat)
    }

    /// The single value of a scalar (or one-element) numeric array.
    pub fn scalar_f64(&self) -> Result<f64> {
        if self.len() != 1 {
            return Err(GeomError::format(
                &self.source,
                format!("expected a scalar, got shape {:?}", self.shape),
            ));
        }
        Ok(self.to_f64()?.iter().next().copied().unwrap_or(f64::NAN))
    }

    /// The single string of a scalar (or one-element) string array.
    pub fn scalar_string(&self) -> Result<String> {
        if self.len() != 1 {
            return Err(GeomError::format(
                &self.source,
                format!("expected a scalar string, got shape {:?}", self.shape),
            ));
        }
        Ok(self.to_strings()?.into_iter().next().unwrap_or_default())
    }

    /// Checks the number of dimensions and, where given, each dimension's size.
    pub fn expect_shape(&self, name: &str, expected: &[Option<usize>]) -> Result<()> {
        let ok = self.shape.len() == expected.len()
            && self
                .shape
                .iter()
                .zip(expected)
                .all(|(&n, e)| e.is_none_or(|e| e == n));
        if ok {
            Ok(())
        } else {
            let want: Vec<String> = expected
                .iter()
                .map(|e| e.map_or("_".to_string(), |v| v.to_string()))
                .collect();
            Err(GeomError::format(
                &self.source,
                format!(
                    "array `{name}` has shape {:?}, expected ({})",
                    self.shape,
                    want.join(", ")
                ),
            ))
        }
    }
}

/// Reads an `.npy` file (any supported dtype; convert with the `to_*` methods).
pub fn read_npy(path: impl AsRef<Path>) -> Result<NpyArray> {
    let path = path.as_ref();
    let bytes = std::fs::read(path).map_err(|e| GeomError::io(path, e))?;
    NpyArray::from_bytes(&bytes, &path.display().to_string())
}

/// An opened `.npz` archive (stored or deflate-compressed).
///
/// The compressed file is held in memory; members are decompressed when read.
#[derive(Debug, Clone)]
pub struct Npz {
    path: PathBuf,
    zip: zip::ZipArchive<Cursor<Arc<[u8]>>>,
    names: Vec<String>,
}

impl Npz {
    /// Opens an `.npz` file. Errors: missing/unreadable file ([`GeomError::Io`]),
    /// not a zip archive ([`GeomError::Format`]).
    pub fn open(path: impl AsRef<Path>) -> Result<Self> {
        let path = path.as_ref();
        let bytes = std::fs::read(path).map_err(|e| GeomError::io(path, e))?;
        Self::from_bytes(bytes, path)
    }

    /// Reads an `.npz` archive from memory; `path` is used in messages.
    pub fn from_bytes(bytes: Vec<u8>, path: impl Into<PathBuf>) -> Result<Self> {
        let path = path.into();
        let data: Arc<[u8]> = Arc::from(bytes);
        let zip = zip::ZipArchive::new(Cursor::new(data)).map_err(|e| {
            GeomError::format(&path, format!("not a valid .npz (zip) archive: {e}"))
        })?;
        let mut names: Vec<String> = zip
            .file_names()
            .map(|n| n.strip_suffix(".npy").unwrap_or(n).to_string())
            .collect();
        names.sort();
        Ok(Npz { path, zip, names })
    }

    /// The file this archive was read from.
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// Array names (without `.npy`), sorted.
    pub fn names(&self) -> &[String] {
        &self.names
    }

    /// Whether an array of that name exists.
    pub fn contains(&self, name: &str) -> bool {
        self.names.iter().any(|n| n == name)
    }

    /// Reads one member without converting it. A missing name is a
    /// [`GeomError::Format`] naming the key and listing the available ones.
    pub fn array(&self, name: &str) -> Result<NpyArray> {
        let source = format!("{}:{name}", self.path.display());
        let mut zip = self.zip.clone();
        let member = if zip.index_for_name(&format!("{name}.npy")).is_some() {
            format!("{name}.npy")
        } else if zip.index_for_name(name).is_some() {
            name.to_string()
        } else {
            return Err(GeomError::format(
                &self.path,
                format!(
                    "no array `{name}` in this npz (available: {})",
                    self.names.join(", ")
                ),
            ));
        };
        let mut file = zip
            .by_name(&member)
            .map_err(|e| GeomError::format(&source, format!("cannot open member: {e}")))?;
        let mut bytes = Vec::with_capacity(usize::try_from(file.size()).unwrap_or(0).min(1 << 28));
        file.read_to_end(&mut bytes)
            .map_err(|e| GeomError::format(&source, format!("corrupt or truncated member: {e}")))?;
        NpyArray::from_bytes(&bytes, &source)
    }

    /// A numeric or boolean array converted to `f64`.
    pub fn array_f64(&self, name: &str) -> Result<ArrayD<f64>> {
        self.array(name)?.to_f64()
    }

    /// An integer or boolean array converted to `i64`.
    pub fn array_i64(&self, name: &str) -> Result<ArrayD<i64>> {
        self.array(name)?.to_i64()
    }

    /// A `<U`/`|S` string array, flattened in standard order.
    pub fn strings(&self, name: &str) -> Result<Vec<String>> {
        self.array(name)?.to_strings()
    }

    /// A scalar numeric array.
    pub fn scalar_f64(&self, name: &str) -> Result<f64> {
        self.array(name)?.scalar_f64()
    }

    /// A scalar string array.
    pub fn scalar_string(&self, name: &str) -> Result<String> {
        self.array(name)?.scalar_string()
    }

    /// A numeric array of fixed rank converted to `f64`, with the shape checked
    /// (`None` = any size for that axis).
    pub fn array_f64_shaped(&self, name: &str, shape: &[Option<usize>]) -> Result<ArrayD<f64>> {
        let a = self.array(name)?;
        a.expect_shape(name, shape)?;
        a.to_f64()
    }
}

/// Encodes strings as a little-endian `<U{n}` `.npy` payload.
pub fn unicode_npy_bytes(strings: &[String], shape: &[usize]) -> Result<Vec<u8>> {
    let count: usize = shape.iter().product();
    if count != strings.len() {
        return Err(GeomError::Shape(format!(
            "{} strings do not fill shape {shape:?}",
            strings.len()
        )));
    }
    let width = strings
        .iter()
        .map(|s| s.chars().count())
        .max()
        .unwrap_or(0)
        .max(1);
    let shape_txt = match shape.len() {
        0 => "()".to_string(),
        1 => format!("({},)", shape[0]),
        _ => format!(
            "({})",
            shape
                .iter()
                .map(|n| n.to_string())
                .collect::<Vec<_>>()
                .join(", ")
        ),
    };
    let dict = format!("{{'descr': '<U{width}', 'fortran_order': False, 'shape': {shape_txt}, }}");
    // Version 1.0 header: magic, version, u16 length, dict padded with spaces
    // and ending in '\n' so that the total is a multiple of 64.
    let unpadded = 6 + 2 + 2 + dict.len() + 1;
    let pad = (64 - unpadded % 64) % 64;
    let header_len = dict.len() + pad + 1;
    let header_len =
        u16::try_from(header_len).map_err(|_| GeomError::Shape("npy header too long".into()))?;
    let mut out = Vec::with_capacity(unpadded + pad + strings.len() * width * 4);
    out.extend_from_slice(b"\x93NUMPY\x01\x00");
    out.extend_from_slice(&header_len.to_le_bytes());
    out.extend_from_slice(dict.as_bytes());
    out.extend(std::iter::repeat_n(b' ', pad));
    out.push(b'\n');
    for s in strings {
        let mut n = 0;
        for c in s.chars() {
            out.extend_from_slice(&(c as u32).to_le_bytes());
            n += 1;
        }
        for _ in n..width {
            out.extend_from_slice(&0u32.to_le_bytes());
        }
    }
    Ok(out)
}

/// Builds an `.npz` archive in memory: numeric arrays through `ndarray-npy`,
/// string arrays as `<U`. Finish with [`NpzOut::finish`] to get the bytes.
pub struct NpzOut {
    zip: zip::ZipWriter<Cursor<Vec<u8>>>,
    options: zip::write::SimpleFileOptions,
}

impl NpzOut {
    /// A new archive; `compressed` selects deflate (as `numpy.savez_compressed`).
    pub fn new(compressed: bool) -> Self {
        let method = if compressed {
            zip::CompressionMethod::Deflated
        } else {
            zip::CompressionMethod::Stored
        };
        NpzOut {
            zip: zip::ZipWriter::new(Cursor::new(Vec::new())),
            options: zip::write::SimpleFileOptions::default()
                .compression_method(method)
                .large_file(false),
        }
    }

    fn member(&mut self, name: &str, bytes: &[u8]) -> Result<()> {
        // A member of 4 GiB or more needs the ZIP64 extensions.
        let large = bytes.len() as u64 >= u64::from(u32::MAX);
        self.zip
            .start_file(format!("{name}.npy"), self.options.large_file(large))
            .map_err(|e| GeomError::format(name, format!("zip: {e}")))?;
        self.zip
            .write_all(bytes)
            .map_err(|e| GeomError::io(name, e))?;
        Ok(())
    }

    /// Adds a numeric array (any type `ndarray-npy` writes: f64, f32, i64, …, bool).
    pub fn add<T: WriteNpyExt + ?Sized>(&mut self, name: &str, array: &T) -> Result<()> {
        let mut buf = Vec::new();
        array
            .write_npy(&mut buf)
            .map_err(|e| GeomError::format(name, format!("cannot encode array: {e}")))?;
        self.member(name, &buf)
    }

    /// Adds a string array of the given shape (`&[]` for a scalar).
    pub fn add_strings(&mut self, name: &str, strings: &[String], shape: &[usize]) -> Result<()> {
        let bytes = unicode_npy_bytes(strings, shape)?;
        self.member(name, &bytes)
    }

    /// Finishes the archive and returns its bytes.
    pub fn finish(self) -> Result<Vec<u8>> {
        let mut cur = self
            .zip
            .finish()
            .map_err(|e| GeomError::format("npz", format!("zip: {e}")))?;
        cur.rewind().map_err(|e| GeomError::io("npz", e))?;
        Ok(cur.into_inner())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn descr_parsing() {
        assert_eq!(parse_descr("<f4"), Some((DType::Float(4), false)));
        assert_eq!(parse_descr(">i8"), Some((DType::Int(8), true)));
        assert_eq!(parse_descr("|b1"), Some((DType::Bool, false)));
        assert_eq!(parse_descr("<U15"), Some((DType::Unicode(15), false)));
        assert_eq!(parse_descr("|S3"), Some((DType::Bytes(3), false)));
        assert_eq!(parse_descr("<f2"), None);
        assert_eq!(parse_descr("|O"), None);
    }

    #[test]
    fn unicode_round_trip_in_memory() {
        let s: Vec<String> = ["a", "héllo", "", "ünï"]
            .iter()
            .map(|s| s.to_string())
            .collect();
        let bytes = unicode_npy_bytes(&s, &[2, 2]).unwrap();
        let a = NpyArray::from_bytes(&bytes, "mem").unwrap();
        assert_eq!(a.shape, vec![2, 2]);
        assert_eq!(a.dtype, DType::Unicode(5));
        assert_eq!(a.to_strings().unwrap(), s);
        assert!(a.to_f64().is_err());
        assert_eq!(bytes.len() % 4, 0);
    }
}
