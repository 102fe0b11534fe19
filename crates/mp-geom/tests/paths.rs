#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)] // test code: failing loudly is the point
#[test]
fn finds_shared_data() {
    // The test suite runs with ../shared beside the checkout.
    let d = mp_geom::data_dir_or_return!();
    assert!(d.join("penn_action").is_dir(), "{}", d.display());
}
