//! BVH export of 3D joint-position tracks: a hierarchy built from the
//! skeleton's bones, fixed bone offsets and per-frame joint rotations, so
//! that forward kinematics ([`Bvh::to_track`]) gives the track back.
//!
//! * **Hierarchy**: the spanning tree of the skeleton's bones that keeps the
//!   most rigid ones (Kruskal on each bone's median absolute deviation of
//!   length: a skeleton that is a tree, as MSR-20 or a BVH's, is kept as it
//!   is; of COCO's loop of shoulders and hips one side is left out); parts
//!   that no bone joins (COCO's face) hang from the joint whose distance to
//!   them changes least. The root is the skeleton's (the hip centre of
//!   MSR-20, a BVH's first joint), else the tree's centre, which keeps the
//!   chains along which errors add up shortest. Names are the joint names
//!   (whitespace and braces become `_`).
//! * **Rest pose**: each bone points along the bone in the rest frame (the
//!   frame with the most joints found, the earliest on ties) and is as long
//!   as its median length; the bones of a joint with several children take
//!   their mean configuration over the frames (each frame's set turned onto
//!   the mean by Kabsch, averaged).
//! * **Rotations**: a joint with one child takes the smallest rotation (in
//!   its parent's frame) that turns its rest bone onto the frame's bone; a
//!   joint with several children the rotation that best aligns all of them
//!   (least squares over the child directions weighted by bone length: the
//!   Kabsch solution through nalgebra's SVD). Where that rotation leaves the
//!   children more than 1 cm off on average (a shoulder that carries both
//!   the arm, which swings, and the side of the torso), each child hangs
//!   from its own zero-length joint `<joint>-<child>` instead, which turns
//!   it exactly. Leaves keep zero rotations and end in an `End Site` at
//!   their own position. Channels: the root `Xposition Yposition Zposition
//!   Zrotation Yrotation Xrotation` (offset 0, the position channels hold
//!   its position), every other joint `Zrotation Yrotation Xrotation`.
//! * **Missing joints** (confidence 0): BVH has no confidence, so every
//!   joint is placed. A joint missing in a frame moves rigidly with its
//!   neighbours along the bones (those found in that frame, from the nearest
//!   frame where it was found with them; else all of them as placed so
//!   far), is interpolated in time where it has no neighbours, and a joint
//!   never found sits at the mean of its neighbours. Bones the source did
//!   not see count a tenth in the rotation fits.
//!
//! Forward kinematics gives each bone's direction exactly (one child) and
//! its median length, so the positions read back differ from the track by
//! the bones' length variation added up along each chain, plus, at joints
//! with several children that are not split, the change of the angles
//! between their bones. Positions are written in metres (the reader's
//! default), the frame time is `1 / fps`. [`super::read_track`] reads a BVH
//! whose joints are a built-in skeleton's (with the zero-length joints
//! between) back as that skeleton.

mod fill;
mod tree;

use glam::{DQuat, DVec3, EulerRot};
use ndarray::Array2;

use super::bvh::{Bvh, BvhJoint, Channel};
use crate::error::{GeomError, Result};
use crate::track::{Track, Units};
use fill::{best_rotation, completed, mean_configurations, point, rest_offsets};
use tree::{neighbours, Tree};

/// Directions shorter than this (in the track's units) count as no direction.
const MIN_LENGTH: f64 = 1e-9;

/// A joint whose children's bones leave more than this (metres, mean over
/// frames and children) from the best common rotation of its rest bones is
/// split: each child hangs from its own zero-length joint.
const SPLIT_MISFIT_M: f64 = 0.01;

/// One joint of the exported hierarchy.
struct Node {
    name: String,
    /// The track joint at this node's place.
    at: usize,
    parent: Option<usize>,
    children: Vec<usize>,
    offset: DVec3,
}

/// The mean (over at most 600 frames and the children) distance between
/// each child of `j` and where the best rotation of its rest bones puts it.
fn misfit(track: &Track, tree: &Tree, offsets: &[DVec3], j: usize) -> f64 {
    let kids: Vec<usize> = tree.children[j]
        .iter()
        .copied()
        .filter(|&c| offsets[c].length() > MIN_LENGTH)
        .collect();
    if kids.len() < 2 {
        return 0.0;
    }
    let from: Vec<DVec3> = kids.iter().map(|&c| offsets[c].normalize()).collect();
    let w: Vec<f64> = kids.iter().map(|&c| offsets[c].length()).collect();
    let step = track.n_frames().div_ceil(600).max(1);
    let (mut sum, mut n) = (0.0, 0usize);
    for t in (0..track.n_frames()).step_by(step) {
        let to: Vec<DVec3> = kids
            .iter()
            .map(|&c| (point(track, t, c) - point(track, t, j)).normalize_or_zero())
            .collect();
        let Some(q) = best_rotation(&from, &to, &w) else {
            continue;
        };
        for k in 0..kids.len() {
            sum += w[k] * (q * from[k] - to[k]).length();
            n += 1;
        }
    }
    if n == 0 {
        0.0
    } else {
        sum / n as f64
    }
}

/// The exported hierarchy in file order: the tree's joints, with a
/// zero-length joint `<joint>-<child>` between each joint that is split and
/// each of its children.
fn nodes(track: &Track, tree: &Tree, offsets: &[DVec3], split: &[bool]) -> Vec<Node> {
    let names = &track.skeleton().joints;
    let mut taken: std::collections::HashSet<String> = names
        .iter()
        .enumerate()
        .map(|(i, n)| bvh_name(n, i))
        .collect();
    let mut out: Vec<Node> = Vec::new();
    // (joint, its split parent's joint for a helper, parent node), popped in pre-order.
    let mut stack = vec![(tree.root, None::<usize>, None::<usize>)];
    while let Some((j, helper_of, parent)) = stack.pop() {
        let me = out.len();
        let (name, at, offset) = match helper_of {
            Some(p) => {
                let mut name = format!("{}-{}", bvh_name(&names[p], p), bvh_name(&names[j], j));
                while !taken.insert(name.clone()) {
                    name.push('_');
                }
                (name, p, DVec3::ZERO)
            }
            None => (
                bvh_name(&names[j], j),
                j,
                if parent.is_some() {
                    offsets[j]
                } else {
                    DVec3::ZERO
                },
            ),
        };
        out.push(Node {
            name,
            at,
            parent,
            children: Vec::new(),
            offset,
        });
        if let Some(p) = parent {
            out[p].children.push(me);
        }
        if helper_of.is_some() {
            // The helper's one child: the joint itself.
            stack.push((j, None, Some(me)));
            continue;
        }
        for &c in tree.children[j].iter().rev() {
            if split[j] {
                stack.push((c, Some(j), Some(me)));
            } else {
                stack.push((c, None, Some(me)));
            }
        }
    }
    out
}

/// A BVH joint name: whitespace and braces (which end names and blocks in
/// the text) become `_`.
fn bvh_name(name: &str, i: usize) -> String {
    let s: String = name
        .chars()
        .map(|c| {
            if c.is_whitespace() || c == '{' || c == '}' {
                '_'
            } else {
                c
            }
        })
        .collect();
    if s.is_empty() {
        format!("j{i}")
    } else {
        s
    }
}

/// The BVH of a 3D joint-position track (see the module docs). A 2D track,
/// a track not in metres and a track without frames or joints are refused.
pub fn track_to_bvh(track: &Track) -> Result<Bvh> {
    if track.dims() != 3 {
        return Err(GeomError::param(
            "track",
            format!(
                "BVH holds 3D motion; this track has {} dimensions per joint (a 2D track \
                 cannot be written as BVH)",
                track.dims()
            ),
        ));
    }
    if track.units() != Units::Metres {
        return Err(GeomError::param(
            "track",
            format!(
                "BVH export needs positions in metres; this track is in `{}`",
                track.units().as_str()
            ),
        ));
    }
    let (t_n, j_n) = (track.n_frames(), track.n_joints());
    if t_n == 0 || j_n == 0 {
        return Err(GeomError::param(
            "track",
            format!("a BVH needs frames and joints; this track has {t_n} frames of {j_n} joints"),
        ));
    }
    let sk = track.skeleton();
    let tree = Tree::of(track);
    // The rest frame: the one with the most joints found (the earliest).
    let rest = (0..t_n)
        .max_by_key(|&t| {
            (
                (0..j_n).filter(|&j| track.is_valid(t, j, 0.0)).count(),
                std::cmp::Reverse(t),
            )
        })
        .unwrap_or(0);
    let source = track;
    let track = &completed(track, &neighbours(sk));
    let mut offsets = rest_offsets(track, &tree, rest);
    mean_configurations(track, source, &tree, &mut offsets);
    let split: Vec<bool> = (0..j_n)
        .map(|j| misfit(track, &tree, &offsets, j) > SPLIT_MISFIT_M)
        .collect();
    let nodes = nodes(track, &tree, &offsets, &split);

    let mut joints = Vec::with_capacity(nodes.len());
    let mut n_channels = 0;
    for n in &nodes {
        let channels = if n.parent.is_none() {
            vec![
                Channel::Xposition,
                Channel::Yposition,
                Channel::Zposition,
                Channel::Zrotation,
                Channel::Yrotation,
                Channel::Xrotation,
            ]
        } else {
            vec![Channel::Zrotation, Channel::Yrotation, Channel::Xrotation]
        };
        joints.push(BvhJoint {
            name: n.name.clone(),
            parent: n.parent,
            offset: n.offset.to_array(),
            first_channel: n_channels,
            end_site: n.children.is_empty().then_some([0.0; 3]),
            channels: channels.clone(),
        });
        n_channels += channels.len();
    }

    let mut motion = Array2::<f64>::zeros((t_n, n_channels));
    // Local rotations of the frame before (kept where a bone has no direction).
    let mut local = vec![DQuat::IDENTITY; nodes.len()];
    let mut global = vec![DQuat::IDENTITY; nodes.len()];
    for t in 0..t_n {
        for (i, n) in nodes.iter().enumerate() {
            let parent_global = n.parent.map_or(DQuat::IDENTITY, |p| global[p]);
            // Rest directions and the frame's directions, in the parent's frame.
            let (mut from, mut to, mut w) = (Vec::new(), Vec::new(), Vec::new());
            let mut kids = 0;
            for &c in &n.children {
                if nodes[c].offset.length() <= MIN_LENGTH {
                    continue;
                }
                kids += 1;
                let d = point(track, t, nodes[c].at) - point(track, t, n.at);
                if d.length() > MIN_LENGTH {
                    from.push(nodes[c].offset.normalize());
                    to.push(parent_global.inverse() * d.normalize());
                    // Bones the source saw count more than made-up ones.
                    let seen =
                        source.is_valid(t, nodes[c].at, 0.0) && source.is_valid(t, n.at, 0.0);
                    w.push(nodes[c].offset.length() * if seen { 1.0 } else { 0.1 });
                }
            }
            let fitted = if from.len() >= 2 {
                best_rotation(&from, &to, &w)
            } else {
                None
            };
            local[i] = match fitted {
                Some(q) => q,
                None if from.len() == 1 && kids == 1 => DQuat::from_rotation_arc(from[0], to[0]),
                None if !from.is_empty() => {
                    // Several children in line (or one with a direction):
                    // turn the longest from where the frame before had it,
                    // keeping the rest of that rotation.
                    let k = (0..from.len())
                        .max_by(|&a, &b| w[a].total_cmp(&w[b]))
                        .unwrap_or(0);
                    let now = local[i] * from[k];
                    (DQuat::from_rotation_arc(now.normalize(), to[k]) * local[i]).normalize()
                }
                None => local[i],
            };
            global[i] = (parent_global * local[i]).normalize();
            let col = joints[i].first_channel;
            let mut row = motion.row_mut(t);
            let rot_col = if n.parent.is_none() {
                let p = point(track, t, n.at);
                for k in 0..3 {
                    row[col + k] = p[k];
                }
                col + 3
            } else {
                col
            };
            let (z, y, x) = local[i].normalize().to_euler(EulerRot::ZYX);
            row[rot_col] = z.to_degrees();
            row[rot_col + 1] = y.to_degrees();
            row[rot_col + 2] = x.to_degrees();
        }
    }
    Bvh::from_parts(joints, 1.0 / track.fps(), motion)
}

/// A track read from a BVH whose joints are those of a built-in skeleton
/// (as [`track_to_bvh`] writes them), perhaps with the zero-length
/// `<joint>-<child>` joints the export adds between: as that skeleton, its
/// joints in its order, with its bones. Any other track as it is.
pub(crate) fn with_builtin_order(track: Track) -> Result<Track> {
    let names = &track.skeleton().joints;
    let mut best: Option<(Vec<usize>, crate::skeleton::Skeleton)> = None;
    for sk in super::builtin_skeletons() {
        if sk.joints == *names {
            return Ok(track);
        }
        let picks: Option<Vec<usize>> = sk
            .joints
            .iter()
            .map(|n| {
                let mut at = names.iter().enumerate().filter(|(_, m)| *m == n);
                match (at.next(), at.next()) {
                    (Some((i, _)), None) => Some(i),
                    _ => None,
                }
            })
            .collect();
        let Some(picks) = picks else { continue };
        let extras_are_helpers = names.iter().enumerate().all(|(i, n)| {
            picks.contains(&i)
                || sk.joints.iter().any(|j| {
                    n.strip_prefix(j.as_str())
                        .is_some_and(|r| r.starts_with('-'))
                })
        });
        if extras_are_helpers && best.as_ref().is_none_or(|(p, _)| p.len() < picks.len()) {
            best = Some((picks, sk));
        }
    }
    match best {
        Some((picks, sk)) => track.select_joints(&picks, sk),
        None => Ok(track),
    }
}
