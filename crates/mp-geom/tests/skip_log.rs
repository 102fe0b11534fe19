//! `paths::data_file_or_skip`: the one test of this binary (its own process),
//! so setting `MP_SKIP_LOG` races with no other test.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)] // test code: failing loudly is the point

use mp_geom::data_dir;
use mp_geom::test_support::data_file_or_skip;

#[test]
fn data_file_or_skip_returns_present_files_and_logs_missing_ones() {
    // A present file comes back as is.
    if let Some(d) = data_dir() {
        if let Some(e) = std::fs::read_dir(&d).unwrap().flatten().next() {
            let rel = e.file_name();
            assert_eq!(data_file_or_skip(&rel, "present"), Some(d.join(&rel)));
        }
    }
    // A missing one is logged, one line per call, appended.
    let dir = std::env::temp_dir().join(format!("mp-skip-log-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let log = dir.join("skips.txt");
    let _ = std::fs::remove_file(&log);
    std::env::set_var("MP_SKIP_LOG", &log);
    let rel = "no-such-data-set/missing.npz";
    assert!(data_file_or_skip(rel, "demo_test").is_none());
    assert!(data_file_or_skip(rel, "other_test").is_none());
    std::env::remove_var("MP_SKIP_LOG");
    let text = std::fs::read_to_string(&log).unwrap();
    assert_eq!(text, format!("demo_test\t{rel}\nother_test\t{rel}\n"));
    let _ = std::fs::remove_dir_all(&dir);
}
