#[test]
fn finds_shared_data() {
    // The test suite runs with ../shared beside the checkout.
    let d = mp_geom::paths::data_dir().expect("shared data folder beside the workspace");
    assert!(d.join("penn_action").is_dir(), "{}", d.display());
}
