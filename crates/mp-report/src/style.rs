//! Colours shared by every picture and the HTML report.

use mp_geom::PrimitiveKind;

/// Fill/stroke colour of a primitive kind.
pub(crate) fn kind_color(kind: PrimitiveKind) -> &'static str {
    match kind {
        PrimitiveKind::Stationary => "#94a3b8",
        PrimitiveKind::Line => "#2563eb",
        PrimitiveKind::Circle => "#ea580c",
        PrimitiveKind::Spline => "#9333ea",
    }
}

/// Colour of the detected keypoints (dots in plots).
pub(crate) const KEYPOINT_DOT: &str = "#475569";
/// Colour of counted repetitions in the timeline and the plots.
pub(crate) const LOOP_FILL: &str = "#14b8a6";
/// Darker repetition colour (repetition boundaries, labels).
pub(crate) const LOOP_DARK: &str = "#0f766e";
/// Colour of the abstract program's loops (its `for` statements) in the timeline.
pub(crate) const PROGRAM_LOOP: &str = "#6366f1";
/// Text colour.
pub(crate) const INK: &str = "#0f172a";
/// Secondary text colour.
pub(crate) const MUTED: &str = "#64748b";
/// Grid lines.
pub(crate) const GRID: &str = "#e2e8f0";
/// Picture background.
pub(crate) const PAPER: &str = "#ffffff";

/// Skeleton colours as RGB: left side, right side, centre, program.
pub(crate) const SKELETON_LEFT: [u8; 3] = [255, 159, 28];
/// Right side of the body.
pub(crate) const SKELETON_RIGHT: [u8; 3] = [56, 189, 248];
/// Bones in the middle and joint dots.
pub(crate) const SKELETON_CENTER: [u8; 3] = [241, 245, 249];
/// The skeleton of the executed program.
pub(crate) const SKELETON_PROGRAM: [u8; 3] = [244, 63, 144];

/// `#rrggbb` of an RGB triple.
pub(crate) fn hex(rgb: [u8; 3]) -> String {
    format!("#{:02x}{:02x}{:02x}", rgb[0], rgb[1], rgb[2])
}

/// Which side of the body a joint name is on: −1 left, 1 right, 0 centre.
pub fn side(name: &str) -> i32 {
    let n = name.to_ascii_lowercase();
    if n.starts_with("left") || n.starts_with("l_") {
        -1
    } else if n.starts_with("right") || n.starts_with("r_") {
        1
    } else {
        0
    }
}

/// Colour of a bone between joints `a` and `b` (by the sides of their names).
pub(crate) fn bone_rgb(a: &str, b: &str) -> [u8; 3] {
    match (side(a) + side(b)).signum() {
        -1 => SKELETON_LEFT,
        1 => SKELETON_RIGHT,
        _ => SKELETON_CENTER,
    }
}
