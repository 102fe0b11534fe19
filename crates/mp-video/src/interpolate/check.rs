//! Whether the pixels bear out the motion the keypoints say: one joint's
//! ([`motion_supported`]) or a whole pair's warp ([`warps_agree`]).

use rayon::prelude::*;

use super::guide::Guide;
use super::warp::{fields, grid_at, lerp1};
use super::{Frames, InterpParams};
use crate::error::Result;

/// Whether the pixels of frames `a` and `b` (RGB, `width × height`) show a
/// patch of half-size `r` moving from `pa` (in `a`) to `pb` (in `b`): the
/// patch of `a` at `pa` matches `b` at `pb` (sum of absolute differences) at
/// least as well as the patch at `pa` or the one at `pb` matches the other
/// frame in place. Uniform patches match everywhere and count as support; a
/// joint the pose model moved while the pixels stayed does not. Patches are
/// clamped to the frame and sampled on a grid of at most 17 × 17 points.
pub fn motion_supported(
    a: &[u8],
    b: &[u8],
    (width, height): (usize, usize),
    pa: [f64; 2],
    pb: [f64; 2],
    r: usize,
) -> bool {
    if width == 0 || height == 0 || a.len() < width * height * 3 || b.len() < a.len() {
        return true;
    }
    if (pa[0] - pb[0]).hypot(pa[1] - pb[1]) < 1.0 {
        return true;
    }
    let at = |p: [f64; 2], dx: isize, dy: isize| {
        let x = (p[0].round() as isize + dx).clamp(0, width as isize - 1) as usize;
        let y = (p[1].round() as isize + dy).clamp(0, height as isize - 1) as usize;
        (y * width + x) * 3
    };
    let sad = |f: &[u8], p: [f64; 2], g: &[u8], q: [f64; 2]| {
        let r = r as isize;
        let step = (r / 8).max(1) as usize;
        let mut s = 0u64;
        for dy in (-r..=r).step_by(step) {
            for dx in (-r..=r).step_by(step) {
                let (i, k) = (at(p, dx, dy), at(q, dx, dy));
                for c in 0..3 {
                    s += f[i + c].abs_diff(g[k + c]) as u64;
                }
            }
        }
        s
    };
    let moved = sad(a, pa, b, pb);
    let stayed = sad(a, pa, b, pa).max(sad(a, pb, b, pb));
    moved <= stayed
}

/// Whether the program's warp of frames `i` and `i + 1` is borne out by
/// their pixels ([`InterpParams::warp_check`]): at the middle time, on the
/// person at the target pose (weighted by the body mask), the mean absolute
/// difference between the two warped frames is at most that between the two
/// frames unwarped. A warp that follows the person's motion brings the two
/// frames together; one driven by keypoints on the background or jumping
/// between frames pulls them apart. `true` where there is nothing to warp.
/// `support` leaves joints in place as in the in-between frames
/// ([`InterpParams::pixel_check`]; `None`: every joint moves).
pub fn warps_agree(
    guide: &Guide,
    frames: &Frames<'_>,
    i: usize,
    params: &InterpParams,
    support: Option<&[bool]>,
) -> Result<bool> {
    let Some(c) = guide.controls(i, 0.5, params, support)? else {
        return Ok(true);
    };
    let (a, b) = (frames.a, frames.b);
    let (width, height) = frames.size;
    let f = fields(&c, params, width, height);
    let (warped, plain) = (0..height)
        .into_par_iter()
        .map(|y| {
            let (mut pa, mut pb) = ([0.0f32; 3], [0.0f32; 3]);
            let (mut dw, mut dp) = (0.0f64, 0.0f64);
            for x in 0..width {
                let m = grid_at(&f.mt, f.gw, f.gf, x, y, lerp1);
                if m <= 0.0 {
                    continue;
                }
                f.sample_both(frames, x, y, &mut pa, &mut pb);
                let p = (y * width + x) * 3;
                for ch in 0..3 {
                    dw += (m * (pa[ch] - pb[ch]).abs()) as f64;
                    dp += (m * (a[p + ch] as f32 - b[p + ch] as f32).abs()) as f64;
                }
            }
            (dw, dp)
        })
        .reduce(|| (0.0, 0.0), |x, y| (x.0 + y.0, x.1 + y.1));
    Ok(warped <= plain)
}

#[cfg(test)]
mod tests {
    use super::{motion_supported, warps_agree};
    use crate::interpolate::{Frames, Guide, InterpParams};

    /// A `w × h` RGB frame: a checkerboard of 4-px cells in a 24-px square
    /// at `(x0, y0)` on a flat grey background.
    fn frame(w: usize, h: usize, x0: usize, y0: usize) -> Vec<u8> {
        let mut f = vec![90u8; w * h * 3];
        for y in y0..(y0 + 24).min(h) {
            for x in x0..(x0 + 24).min(w) {
                let v = if ((x - x0) / 4 + (y - y0) / 4).is_multiple_of(2) {
                    20
                } else {
                    230
                };
                f[(y * w + x) * 3..(y * w + x) * 3 + 3].fill(v);
            }
        }
        f
    }

    #[test]
    fn motion_the_pixels_show_is_supported() {
        let (w, h) = (120, 80);
        let (a, b) = (frame(w, h, 20, 20), frame(w, h, 50, 30));
        // The square's centre moves with the keypoint.
        assert!(motion_supported(
            &a,
            &b,
            (w, h),
            [32.0, 32.0],
            [62.0, 42.0],
            8
        ));
    }

    #[test]
    fn a_keypoint_jump_on_still_pixels_is_not_supported() {
        let (w, h) = (120, 80);
        let a = frame(w, h, 20, 20);
        assert!(!motion_supported(
            &a,
            &a,
            (w, h),
            [32.0, 32.0],
            [70.0, 50.0],
            8
        ));
        // Less than a pixel, a uniform background, and frames of the wrong
        // size count as support (nothing to contradict the keypoints).
        assert!(motion_supported(
            &a,
            &a,
            (w, h),
            [32.0, 32.0],
            [32.5, 32.0],
            8
        ));
        let grey = vec![90u8; w * h * 3];
        assert!(motion_supported(
            &grey,
            &grey,
            (w, h),
            [5.0, 5.0],
            [90.0, 60.0],
            8
        ));
        assert!(motion_supported(
            &a,
            &a[..10],
            (w, h),
            [32.0, 32.0],
            [70.0, 50.0],
            8
        ));
        // Patches at the border are clamped to the frame.
        assert!(!motion_supported(
            &a,
            &a,
            (w, h),
            [0.0, 0.0],
            [30.0, 30.0],
            8
        ));
    }

    /// A `w × h` frame of grey with a textured 48 × 48 square at `(x0, y0)`.
    fn textured(w: usize, h: usize, x0: usize, y0: usize) -> Vec<u8> {
        let mut f = vec![90u8; w * h * 3];
        for y in y0..(y0 + 48).min(h) {
            for x in x0..(x0 + 48).min(w) {
                let (u, v) = ((x - x0) as u32, (y - y0) as u32);
                let n = (u.wrapping_mul(73_856_093) ^ v.wrapping_mul(19_349_663)) % 251;
                f[(y * w + x) * 3..(y * w + x) * 3 + 3].fill(n as u8);
            }
        }
        f
    }

    /// A guide whose 17 keypoints sit on a 4 × 5 grid inside the square at
    /// `x0` in frame 0 and at `x1` in frame 1.
    fn guide(x0: f64, x1: f64, y0: f64) -> Guide {
        use mp_geom::{Skeleton, Track, Units};
        let mut pos = ndarray::Array3::<f64>::zeros((2, 17, 2));
        for (t, x) in [x0, x1].into_iter().enumerate() {
            for j in 0..17 {
                pos[[t, j, 0]] = x + 6.0 + 9.0 * (j % 4) as f64;
                pos[[t, j, 1]] = y0 + 5.0 + 9.0 * (j / 4) as f64;
            }
        }
        let track = Track::new(pos, None, 30.0, Units::Pixels, Skeleton::coco17()).unwrap();
        let program = mp_concrete::Program::synthesize(&track, &Default::default()).unwrap();
        Guide {
            track,
            program,
            inbetween: mp_concrete::InBetween::default(),
            min_confidence: 0.3,
        }
    }

    #[test]
    fn a_warp_that_follows_the_pixels_agrees_and_one_that_does_not_disagrees() {
        let (w, h) = (160, 100);
        let params = InterpParams::default();
        // The square moves 12 px to the right and the keypoints with it.
        let (a, b) = (textured(w, h, 40, 20), textured(w, h, 52, 20));
        let moving = Frames {
            a: &a,
            b: &b,
            size: (w, h),
        };
        let g = guide(40.0, 52.0, 20.0);
        assert!(warps_agree(&g, &moving, 0, &params, None).unwrap());
        // The pixels stay while the keypoints move: the warp pulls the two
        // frames apart.
        let still = Frames {
            a: &a,
            b: &a,
            size: (w, h),
        };
        assert!(!warps_agree(&g, &still, 0, &params, None).unwrap());
        // Keypoints that stay on still pixels: nothing moves, they agree.
        let g = guide(40.0, 40.0, 20.0);
        assert!(warps_agree(&g, &still, 0, &params, None).unwrap());
    }
}
