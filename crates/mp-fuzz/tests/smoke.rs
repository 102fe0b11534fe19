//! Every fuzz target over its seed corpus (`corpus/<target>/`), then a
//! bounded, deterministic mutation loop (bit flips, byte inserts and
//! deletes, splices between corpus files) with a fixed seed. No input may
//! make a target panic; a panicking input is reported (its bytes escaped)
//! so that it can become a regression test in the crate that owns the
//! reader.

use std::panic::{catch_unwind, AssertUnwindSafe};
use std::path::{Path, PathBuf};

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

/// Mutated inputs per target (all targets together stay well under a
/// minute in the dev profile on two cores).
const MUTATIONS: usize = 5000;
/// Bytes of a panicking input shown in the report (all of it is saved).
const SHOWN: usize = 2048;
/// Mutants are cut to this many bytes.
const MAX_LEN: usize = 64 * 1024;

fn corpus_dir(target: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("corpus")
        .join(target)
}

/// The seed files of `target`, sorted by name (none when the folder is missing).
fn read_corpus(target: &str) -> Vec<(String, Vec<u8>)> {
    let Ok(entries) = std::fs::read_dir(corpus_dir(target)) else {
        return Vec::new();
    };
    let mut files: Vec<PathBuf> = entries
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.is_file())
        .collect();
    files.sort();
    files
        .into_iter()
        .filter_map(|p| {
            let name = p.file_name()?.to_string_lossy().into_owned();
            Some((name, std::fs::read(&p).ok()?))
        })
        .collect()
}

fn escaped(data: &[u8]) -> String {
    data.iter()
        .flat_map(|&b| std::ascii::escape_default(b))
        .map(char::from)
        .collect()
}

/// Runs `f` on `data`; on a panic, the description of the input and its bytes.
fn run(f: mp_fuzz::Target, data: &[u8]) -> Result<(), String> {
    catch_unwind(AssertUnwindSafe(|| f(data))).map_err(|e| {
        let msg = e
            .downcast_ref::<String>()
            .cloned()
            .or_else(|| e.downcast_ref::<&str>().map(|s| s.to_string()))
            .unwrap_or_default();
        let shown = &data[..data.len().min(SHOWN)];
        let more = if data.len() > SHOWN { "…" } else { "" };
        format!(
            "{msg}\n  input ({} bytes): b\"{}\"{more}",
            data.len(),
            escaped(shown)
        )
    })
}

/// Saves a panicking input under the test's temporary folder; returns its path.
fn save_failure(target: &str, i: usize, data: &[u8]) -> String {
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR")).join("fuzz-failures");
    let path = dir.join(format!("{target}-{i}"));
    match std::fs::create_dir_all(&dir).and_then(|()| std::fs::write(&path, data)) {
        Ok(()) => path.display().to_string(),
        Err(e) => format!("<not saved: {e}>"),
    }
}

fn mutate(rng: &mut ChaCha8Rng, corpus: &[(String, Vec<u8>)]) -> Vec<u8> {
    let mut d = corpus[rng.random_range(0..corpus.len())].1.clone();
    for _ in 0..rng.random_range(1..=4) {
        match rng.random_range(0..6) {
            0 if !d.is_empty() => {
                let i = rng.random_range(0..d.len());
                d[i] ^= 1 << rng.random_range(0..8);
            }
            1 => {
                let i = rng.random_range(0..=d.len());
                let interesting = [
                    b'0', b'9', b'-', b'.', b',', b'"', b'{', b'}', 0, 0xff, b'e',
                ];
                let b = if rng.random_bool(0.5) {
                    interesting[rng.random_range(0..interesting.len())]
                } else {
                    rng.random()
                };
                d.insert(i, b);
            }
            2 if !d.is_empty() => {
                let i = rng.random_range(0..d.len());
                let n = rng.random_range(1..=16).min(d.len() - i);
                d.drain(i..i + n);
            }
            3 => {
                // Splice: a piece of another corpus file.
                let other = &corpus[rng.random_range(0..corpus.len())].1;
                if !other.is_empty() {
                    let a = rng.random_range(0..other.len());
                    let b = rng.random_range(a..=other.len().min(a + 256));
                    let at = rng.random_range(0..=d.len());
                    d.splice(at..at, other[a..b].iter().copied());
                }
            }
            4 if !d.is_empty() => {
                // Overwrite with a boundary value.
                let i = rng.random_range(0..d.len());
                let v: &[u8] = match rng.random_range(0..4) {
                    0 => b"1e308",
                    1 => b"-0",
                    2 => b"18446744073709551615",
                    _ => &[0xff, 0xff, 0xff, 0xff, 0xff, 0xff, 0xff, 0x7f],
                };
                let end = (i + v.len()).min(d.len());
                d.splice(i..end, v.iter().copied());
            }
            _ if !d.is_empty() => {
                // Duplicate a chunk.
                let a = rng.random_range(0..d.len());
                let b = rng.random_range(a..=d.len().min(a + 64));
                let chunk = d[a..b].to_vec();
                d.splice(b..b, chunk);
            }
            _ => d.push(rng.random()),
        }
    }
    d.truncate(MAX_LEN);
    d
}

#[test]
fn every_target_has_a_seed_corpus() {
    for (name, _) in mp_fuzz::TARGETS {
        assert!(
            !read_corpus(name).is_empty(),
            "no seed corpus for target `{name}`"
        );
        assert!(mp_fuzz::target(name).is_some());
    }
}

#[test]
fn targets_survive_corpus_and_mutations() {
    let mut failures = Vec::new();
    for (ti, (name, f)) in mp_fuzz::TARGETS.iter().enumerate() {
        let corpus = read_corpus(name);
        for (file, data) in &corpus {
            if let Err(e) = run(*f, data) {
                failures.push(format!("{name}: corpus file {file}: {e}"));
            }
        }
        let mut rng = ChaCha8Rng::seed_from_u64(0x6d70_6675_7a7a + ti as u64);
        for i in 0..MUTATIONS {
            let d = mutate(&mut rng, &corpus);
            if let Err(e) = run(*f, &d) {
                let saved = save_failure(name, i, &d);
                failures.push(format!("{name}: mutant {i} (saved as {saved}): {e}"));
            }
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

/// The people seeds are valid files: each reads with the reader of its
/// form, so the `people` target checks a result on every seed, not only
/// errors.
#[test]
fn people_seeds_read() {
    use mp_geom::fuzzing::npz::Npz;
    use mp_geom::fuzzing::people::{people_from_bincode, people_from_json_str, people_from_npz};

    let corpus = read_corpus("people");
    for ext in ["npz", "json", "mpt"] {
        assert!(
            corpus.iter().any(|(n, _)| n.ends_with(ext)),
            "no `.{ext}` seed for target `people`"
        );
    }
    for (name, data) in &corpus {
        let read = match name.rsplit('.').next() {
            Some("npz") => {
                Npz::from_bytes(data.clone(), name.as_str()).and_then(|z| people_from_npz(&z))
            }
            Some("json") => std::str::from_utf8(data)
                .map_err(|e| mp_geom::GeomError::format(name.as_str(), e.to_string()))
                .and_then(|s| people_from_json_str(s, Path::new(name))),
            Some("mpt") => people_from_bincode(data),
            _ => continue,
        };
        assert!(read.is_ok(), "seed {name} does not read: {:?}", read.err());
        assert!(data.len() < 20 * 1024, "seed {name} is over 20 KB");
    }
}
