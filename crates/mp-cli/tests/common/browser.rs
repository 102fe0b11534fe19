//! The report page in headless Chromium, opened from disk as a user opens
//! it: the DOM after its script ran, and what the page says about itself.

use std::path::Path;
use std::process::{Command, Output};

/// Runs headless Chromium on `page` with a URL fragment (`#frame=55`, or
/// empty) and the given extra arguments (`--dump-dom`, `--screenshot=…`).
pub fn chromium_at(page: &Path, fragment: &str, profile: &Path, extra: &[&str]) -> Output {
    let url = format!(
        "file://{}{fragment}",
        page.canonicalize().unwrap().display()
    );
    headless(profile)
        .arg("--virtual-time-budget=3000")
        .args(extra)
        .arg(url)
        .output()
        .expect("cannot start Chromium")
}

/// Headless Chromium with a fresh profile and a fixed window, as every test
/// runs it.
fn headless(profile: &Path) -> Command {
    let exe = ["/usr/bin/chromium", "/usr/bin/chromium-browser"]
        .into_iter()
        .find(|p| Path::new(p).exists())
        .expect("Chromium not found at /usr/bin/chromium (scripts/setup.sh installs the Debian package)");
    let mut cmd = Command::new(exe);
    cmd.args([
        "--headless",
        "--no-sandbox",
        "--disable-gpu",
        "--disable-background-networking",
        "--disable-component-update",
        "--disable-sync",
        "--no-first-run",
        "--hide-scrollbars",
        "--window-size=1280,900",
    ])
    .arg(format!("--user-data-dir={}", profile.display()));
    cmd
}

/// The start tag of the element whose start tag begins with `start` (e.g.
/// `<canvas id="stage"`), in a DOM dump.
pub fn start_tag<'a>(dom: &'a str, start: &str) -> &'a str {
    dom.split(start)
        .nth(1)
        .and_then(|s| s.split('>').next())
        .unwrap_or_else(|| panic!("no {start} in the DOM:\n{}", &dom[..dom.len().min(2000)]))
}

/// An attribute's value in a start tag.
pub fn attr<'a>(tag: &'a str, name: &str) -> Option<&'a str> {
    tag.split(&format!(" {name}=\"")).nth(1)?.split('"').next()
}

/// The page's status element (`<div id="mp-status" …>text`).
pub fn status(dom: &str) -> &str {
    dom.split("<div id=\"mp-status\"")
        .nth(1)
        .and_then(|s| s.split("</div>").next())
        .unwrap_or_else(|| {
            panic!(
                "status element missing from the DOM:\n{}",
                &dom[..dom.len().min(2000)]
            )
        })
}

/// Opens `page` at `fragment` and checks that the page got ready without
/// an error, showed the picture of video frame `picture` (when it has
/// frames) and drew the keypoints of frame `drawn` (when it has keypoints).
/// Returns the DOM.
pub fn check_opens_at(
    page: &Path,
    fragment: &str,
    profile: &Path,
    picture: Option<usize>,
    drawn: Option<usize>,
) -> String {
    let out = chromium_at(
        page,
        fragment,
        profile,
        &["--dump-dom", "--enable-logging=stderr", "--v=0"],
    );
    let dom = String::from_utf8_lossy(&out.stdout).into_owned();
    let log = String::from_utf8_lossy(&out.stderr);
    assert!(!log.contains("Uncaught"), "script errors:\n{log}");
    let st = status(&dom);
    assert!(st.contains("data-errors=\"0\""), "{fragment}: {st}");
    assert!(st.contains("data-ready=\"1\""), "{fragment}: {st}");
    assert!(st.trim_end().ends_with(">ok"), "{fragment}: {st}");
    let stage = start_tag(&dom, "<canvas id=\"stage\"");
    assert_eq!(
        attr(stage, "data-picture"),
        picture.map(|p| p.to_string()).as_deref(),
        "{fragment}: the picture shown ({stage})"
    );
    assert_eq!(
        attr(stage, "data-drawn"),
        drawn.map(|p| p.to_string()).as_deref(),
        "{fragment}: the keypoints drawn ({stage})"
    );
    dom
}

/// Runs headless Chromium on a live `url` (a page served by `mp live
/// --serve`) for `wait_ms` of real time (the page never finishes loading
/// while its streams are open), with the given extra arguments
/// (`--dump-dom`, `--screenshot=…`).
pub fn chromium_live(url: &str, profile: &Path, wait_ms: u32, extra: &[&str]) -> Output {
    headless(profile)
        .arg(format!("--timeout={wait_ms}"))
        .args(extra)
        .arg(url)
        .output()
        .expect("cannot start Chromium")
}
