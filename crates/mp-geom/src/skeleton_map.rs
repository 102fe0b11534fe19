//! Mappings between skeletons, for running a model of one skeleton on the
//! tracks of another.
//!
//! A [`SkeletonMap`] says how each joint of a *target* skeleton is made from
//! the joints of a *source* skeleton ([`JointSource`]: one joint, or a
//! weighted mean of several), with optional axis sign flips (BlazePose's
//! world landmarks have y down, MSR Action3D's camera space y up).
//! [`SkeletonMap::apply`] maps a track forward; [`SkeletonMap::carry_back`]
//! puts a motion of the target skeleton (a forecast, a refinement) back on
//! the source's joints:
//!
//! * a source joint that *is* a target joint takes that joint's output;
//! * every other source joint is carried rigidly (translated) with its
//!   **carrier**: the target joint it contributes most to (the ears carry
//!   with an MSR head made from them), else the target joint nearest to it
//!   in the reference frames (an eye with the head, a heel with the ankle).
//!   Its output is its reference position plus the carrier's displacement
//!   from the carrier's own reference position;
//! * a joint that has no valid carrier is held at its reference position.
//!
//! The built-in maps ([`SkeletonMap::builtin`]):
//!
//! | source | target | how |
//! |---|---|---|
//! | any with a COCO-17 mapping | `coco17` | the skeleton's COCO joints ([`SkeletonMap::to_coco17`]) |
//! | `coco17` (2D or 3D) | `penn13` | joint selection, the nose as the head |
//! | `blazepose33` | `penn13` | through its COCO-17 joints |
//! | `blazepose33` world landmarks (3D) | `msr20` | y flipped (up); hip centre = mean of the hips; neck = mean of the shoulders; spine = midway between them; hand = mean of the index and pinky knuckles; foot = foot index; head = mean of the ears; the other joints selected |

use ndarray::{Array2, Array3};

use crate::error::{GeomError, Result};
use crate::skeleton::Skeleton;
use crate::track::Track;

/// How one target joint is made from the source skeleton's joints.
#[derive(Debug, Clone, PartialEq)]
#[non_exhaustive]
pub enum JointSource {
    /// The source joint itself.
    Joint(usize),
    /// `Σ wᵢ · joint ᵢ` with weights summing to 1 (a mean or a point between joints).
    Blend(Vec<(usize, f64)>),
}

impl JointSource {
    /// The mean of the given source joints.
    pub fn mean(joints: &[usize]) -> Self {
        let w = 1.0 / joints.len().max(1) as f64;
        JointSource::Blend(joints.iter().map(|&j| (j, w)).collect())
    }

    /// The `(joint, weight)` terms.
    pub fn terms(&self) -> Vec<(usize, f64)> {
        match self {
            JointSource::Joint(j) => vec![(*j, 1.0)],
            JointSource::Blend(t) => t.clone(),
        }
    }

    /// Normalised form: a single term of weight 1 is a [`JointSource::Joint`].
    fn normalised(terms: Vec<(usize, f64)>) -> Self {
        match terms.as_slice() {
            [(j, w)] if (*w - 1.0).abs() < 1e-12 => JointSource::Joint(*j),
            _ => JointSource::Blend(terms),
        }
    }
}

/// Which reference frame an output frame is carried back from.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[non_exhaustive]
pub enum FramePairing {
    /// Output frame `f` with reference frame `f` (same frame count): a
    /// refinement of the reference.
    SameFrame,
    /// Every output frame with the latest reference frame in which the joint
    /// and its carrier are valid: a forecast after the reference.
    LastFrame,
}

/// A mapping from a source skeleton onto a target skeleton (see the module docs).
#[derive(Debug, Clone, PartialEq)]
pub struct SkeletonMap {
    source: Skeleton,
    target: Skeleton,
    sources: Vec<JointSource>,
    axis_signs: [f64; 3],
    dims: Option<usize>,
}

impl SkeletonMap {
    /// A map from `source` to `target`: `sources[a]` makes target joint `a`;
    /// target coordinate `k` is multiplied by `axis_signs[k]` (each ±1).
    /// Errors: a source list of the wrong length, a joint index out of range,
    /// an empty blend, weights that are not finite or do not sum to 1, a
    /// sign other than ±1.
    pub fn new(
        source: Skeleton,
        target: Skeleton,
        sources: Vec<JointSource>,
        axis_signs: [f64; 3],
    ) -> Result<Self> {
        if sources.len() != target.len() {
            return Err(GeomError::Shape(format!(
                "map {} → {}: {} joint sources for {} target joints",
                source.name,
                target.name,
                sources.len(),
                target.len()
            )));
        }
        for (a, s) in sources.iter().enumerate() {
            let terms = s.terms();
            let sum: f64 = terms.iter().map(|t| t.1).sum();
            if terms.is_empty()
                || terms
                    .iter()
                    .any(|&(j, w)| j >= source.len() || !w.is_finite())
                || (sum - 1.0).abs() > 1e-9
            {
                return Err(GeomError::param(
                    "sources",
                    format!(
                        "map {} → {}: target joint `{}` needs source joints in 0..{} with weights summing to 1, got {terms:?}",
                        source.name, target.name, target.joints[a], source.len()
                    ),
                ));
            }
        }
        if axis_signs.iter().any(|s| s.abs() != 1.0) {
            return Err(GeomError::param(
                "axis_signs",
                format!("each must be 1 or −1, got {axis_signs:?}"),
            ));
        }
        Ok(SkeletonMap {
            source,
            target,
            sources,
            axis_signs,
            dims: None,
        })
    }

    /// The same map, restricted to tracks of `dims` coordinates per joint.
    pub fn for_dims(mut self, dims: usize) -> Self {
        self.dims = Some(dims);
        self
    }

    /// The identity map of a skeleton.
    pub fn identity(skeleton: &Skeleton) -> Self {
        SkeletonMap {
            source: skeleton.clone(),
            target: skeleton.clone(),
            sources: (0..skeleton.len()).map(JointSource::Joint).collect(),
            axis_signs: [1.0; 3],
            dims: None,
        }
    }

    /// Every target joint from the source joint of the same name, except
    /// the target joints named in `overrides`.
    pub fn by_names(
        source: &Skeleton,
        target: &Skeleton,
        overrides: &[(&str, JointSource)],
        axis_signs: [f64; 3],
    ) -> Result<Self> {
        let sources = target
            .joints
            .iter()
            .map(|name| {
                if let Some((_, s)) = overrides.iter().find(|(n, _)| n == name) {
                    return Ok(s.clone());
                }
                source
                    .joint_index(name)
                    .map(JointSource::Joint)
                    .ok_or_else(|| GeomError::Unknown {
                        kind: "joint (for the skeleton map)",
                        name: format!("{name} in `{}`", source.name),
                    })
            })
            .collect::<Result<Vec<_>>>()?;
        Self::new(source.clone(), target.clone(), sources, axis_signs)
    }

    /// A skeleton's own COCO-17 joints (errors when it has no complete mapping).
    pub fn to_coco17(source: &Skeleton) -> Result<Self> {
        let idx: Option<Vec<usize>> = source.coco17.iter().copied().collect();
        match idx {
            Some(idx) if idx.len() == 17 => Self::new(
                source.clone(),
                Skeleton::coco17(),
                idx.into_iter().map(JointSource::Joint).collect(),
                [1.0; 3],
            ),
            _ => Err(GeomError::NoData(format!(
                "skeleton `{}` has no complete mapping to COCO-17",
                source.name
            ))),
        }
    }

    /// COCO-17 → Penn Action-13: a joint selection with the nose as the head.
    pub fn coco17_to_penn13() -> Result<Self> {
        Self::by_names(
            &Skeleton::coco17(),
            &Skeleton::penn13(),
            &[("head", JointSource::Joint(0))],
            [1.0; 3],
        )
    }

    /// BlazePose-33 → Penn Action-13, through BlazePose's COCO-17 joints.
    pub fn blazepose33_to_penn13() -> Result<Self> {
        Self::to_coco17(&Skeleton::blazepose33())?.then(&Self::coco17_to_penn13()?)
    }

    /// BlazePose-33 world landmarks (3D, metres, hip-centred, y down) →
    /// MSR Action3D-20 (y up), see the module docs.
    pub fn blazepose33_world_to_msr20() -> Result<Self> {
        let b = Skeleton::blazepose33();
        let i = |n: &str| {
            b.joint_index(n).ok_or_else(|| GeomError::Unknown {
                kind: "BlazePose-33 joint",
                name: n.to_string(),
            })
        };
        let (ls, rs, lh, rh) = (
            i("left_shoulder")?,
            i("right_shoulder")?,
            i("left_hip")?,
            i("right_hip")?,
        );
        let overrides = [
            ("neck", JointSource::mean(&[ls, rs])),
            ("spine", JointSource::mean(&[ls, rs, lh, rh])),
            ("hip_centre", JointSource::mean(&[lh, rh])),
            (
                "right_hand",
                JointSource::mean(&[i("right_index")?, i("right_pinky")?]),
            ),
            (
                "left_hand",
                JointSource::mean(&[i("left_index")?, i("left_pinky")?]),
            ),
            ("right_foot", JointSource::Joint(i("right_foot_index")?)),
            ("left_foot", JointSource::Joint(i("left_foot_index")?)),
            (
                "head",
                JointSource::mean(&[i("left_ear")?, i("right_ear")?]),
            ),
        ];
        Ok(Self::by_names(&b, &Skeleton::msr20(), &overrides, [1.0, -1.0, 1.0])?.for_dims(3))
    }

    /// The built-in map from `source` to the built-in skeleton `target` (see
    /// the module docs). Errors name the pairs that exist.
    pub fn builtin(source: &Skeleton, target: &str) -> Result<Self> {
        let target = Skeleton::by_name(target)?;
        if source.joints == target.joints {
            return Ok(Self::identity(source));
        }
        match (source.name.as_str(), target.name.as_str()) {
            ("coco17", "penn13") => Self::coco17_to_penn13(),
            ("blazepose33", "penn13") => Self::blazepose33_to_penn13(),
            ("blazepose33", "msr20") => Self::blazepose33_world_to_msr20(),
            (_, "coco17") => Self::to_coco17(source),
            (s, t) => Err(GeomError::NoData(format!(
                "no mapping from skeleton `{s}` to `{t}` (there are: coco17 → penn13, \
                 blazepose33 → penn13, blazepose33 world landmarks → msr20, any → coco17)"
            ))),
        }
    }

    /// `self` followed by `next` (whose source must be this map's target).
    pub fn then(&self, next: &SkeletonMap) -> Result<Self> {
        if next.source.joints != self.target.joints {
            return Err(GeomError::Shape(format!(
                "cannot chain {} → {} with {} → {}",
                self.source.name, self.target.name, next.source.name, next.target.name
            )));
        }
        let sources = next
            .sources
            .iter()
            .map(|s| {
                let mut terms: Vec<(usize, f64)> = Vec::new();
                for (mid, w) in s.terms() {
                    for (j, v) in self.sources[mid].terms() {
                        match terms.iter_mut().find(|t| t.0 == j) {
                            Some(t) => t.1 += w * v,
                            None => terms.push((j, w * v)),
                        }
                    }
                }
                JointSource::normalised(terms)
            })
            .collect();
        let mut signs = [1.0; 3];
        for (k, s) in signs.iter_mut().enumerate() {
            *s = self.axis_signs[k] * next.axis_signs[k];
        }
        let mut m = Self::new(self.source.clone(), next.target.clone(), sources, signs)?;
        m.dims = self.dims.or(next.dims);
        Ok(m)
    }

    /// The source skeleton.
    pub fn source(&self) -> &Skeleton {
        &self.source
    }
    /// The target skeleton.
    pub fn target(&self) -> &Skeleton {
        &self.target
    }
    /// How each target joint is made.
    pub fn sources(&self) -> &[JointSource] {
        &self.sources
    }
    /// Sign of each target axis.
    pub fn axis_signs(&self) -> [f64; 3] {
        self.axis_signs
    }
    /// The coordinates per joint the map is restricted to, if any.
    pub fn dims(&self) -> Option<usize> {
        self.dims
    }

    fn check_source(&self, track: &Track, what: &str) -> Result<()> {
        if track.skeleton().joints != self.source.joints {
            return Err(GeomError::Shape(format!(
                "map {} → {}: the {what} has skeleton `{}` ({} joints), not `{}`",
                self.source.name,
                self.target.name,
                track.skeleton().name,
                track.n_joints(),
                self.source.name
            )));
        }
        if let Some(d) = self.dims.filter(|&d| d != track.dims()) {
            return Err(GeomError::Shape(format!(
                "map {} → {} needs {d}D positions, the {what} has {}D",
                self.source.name,
                self.target.name,
                track.dims()
            )));
        }
        Ok(())
    }

    /// The track on the target skeleton. A target joint's confidence is the
    /// smallest confidence of its source joints.
    pub fn apply(&self, track: &Track) -> Result<Track> {
        self.check_source(track, "track")?;
        let (t, _, d) = track.positions().dim();
        let p = track.positions();
        let c = track.confidence();
        let n = self.target.len();
        let mut pos = Array3::zeros((t, n, d));
        let mut conf = Array2::zeros((t, n));
        for (a, s) in self.sources.iter().enumerate() {
            let terms = s.terms();
            for f in 0..t {
                for k in 0..d {
                    let v: f64 = terms.iter().map(|&(j, w)| w * p[[f, j, k]]).sum();
                    pos[[f, a, k]] = self.sign(k) * v;
                }
                conf[[f, a]] = terms
                    .iter()
                    .map(|&(j, _)| c[[f, j]])
                    .fold(f64::INFINITY, f64::min);
            }
        }
        Track::new(
            pos,
            Some(conf),
            track.fps(),
            track.units(),
            self.target.clone(),
        )
    }

    fn sign(&self, k: usize) -> f64 {
        self.axis_signs.get(k).copied().unwrap_or(1.0)
    }

    /// The carrier of each source joint (see the module docs): the target
    /// joint that is this joint, else the target joint it weighs most in,
    /// else the target joint nearest to it on average over the frames of
    /// `reference` where both are valid; `None` when there is no such frame.
    pub fn carriers(&self, reference: &Track) -> Result<Vec<Carrier>> {
        let mapped = self.apply(reference)?;
        Ok(self.carriers_with(reference, &mapped))
    }

    fn carriers_with(&self, reference: &Track, mapped: &Track) -> Vec<Carrier> {
        (0..self.source.len())
            .map(|j| {
                if let Some(a) = self
                    .sources
                    .iter()
                    .position(|s| *s == JointSource::Joint(j))
                {
                    return Carrier::Is(a);
                }
                let weighed = self
                    .sources
                    .iter()
                    .enumerate()
                    .filter_map(|(a, s)| {
                        s.terms()
                            .iter()
                            .find(|t| t.0 == j && t.1 > 0.0)
                            .map(|t| (a, t.1))
                    })
                    .fold(None, |best: Option<(usize, f64)>, (a, w)| match best {
                        Some((_, bw)) if bw >= w => best,
                        _ => Some((a, w)),
                    });
                if let Some((a, _)) = weighed {
                    return Carrier::Moves(a);
                }
                self.nearest(j, reference, mapped)
                    .map_or(Carrier::Held, Carrier::Moves)
            })
            .collect()
    }

    /// The target joint nearest to source joint `j` in `reference` (mean
    /// distance over the frames where both are valid, in target axes).
    fn nearest(&self, j: usize, reference: &Track, mapped: &Track) -> Option<usize> {
        let (t, _, d) = reference.positions().dim();
        let (p, c) = (reference.positions(), reference.confidence());
        let (q, qc) = (mapped.positions(), mapped.confidence());
        (0..self.target.len())
            .filter_map(|a| {
                let (mut sum, mut n) = (0.0, 0usize);
                for f in (0..t).filter(|&f| c[[f, j]] > 0.0 && qc[[f, a]] > 0.0) {
                    let d2: f64 = (0..d)
                        .map(|k| (self.sign(k) * p[[f, j, k]] - q[[f, a, k]]).powi(2))
                        .sum();
                    sum += d2.sqrt();
                    n += 1;
                }
                (n > 0).then(|| (a, sum / n as f64))
            })
            .min_by(|x, y| x.1.total_cmp(&y.1))
            .map(|(a, _)| a)
    }

    /// Puts `output` (a motion of the target skeleton) back on the source
    /// joints of `reference` (see the module docs); `pairing` says which
    /// reference frame each output frame is carried from. The result has
    /// the source skeleton, `output`'s frames, frame rate and units.
    pub fn carry_back(
        &self,
        reference: &Track,
        output: &Track,
        pairing: FramePairing,
    ) -> Result<Track> {
        let mapped = self.apply(reference)?;
        self.carry_back_with(reference, &mapped, output, pairing)
    }

    /// [`SkeletonMap::carry_back`] with the mapped reference given (e.g.
    /// the mapped track after its missing joints were filled, as the model saw it).
    pub fn carry_back_with(
        &self,
        reference: &Track,
        mapped: &Track,
        output: &Track,
        pairing: FramePairing,
    ) -> Result<Track> {
        self.check_source(reference, "reference")?;
        let (tr, _, d) = reference.positions().dim();
        if mapped.skeleton().joints != self.target.joints || mapped.n_frames() != tr {
            return Err(GeomError::Shape(format!(
                "map {} → {}: the mapped reference must have the target skeleton and {tr} frames",
                self.source.name, self.target.name
            )));
        }
        if output.skeleton().joints != self.target.joints || output.dims() != d {
            return Err(GeomError::Shape(format!(
                "map {} → {}: the output has skeleton `{}` in {}D, expected `{}` in {d}D",
                self.source.name,
                self.target.name,
                output.skeleton().name,
                output.dims(),
                self.target.name
            )));
        }
        let to = output.n_frames();
        if pairing == FramePairing::SameFrame && to != tr {
            return Err(GeomError::Shape(format!(
                "carrying back frame by frame needs as many output frames ({to}) as reference frames ({tr})"
            )));
        }
        if tr == 0 {
            return Err(GeomError::TooShort {
                what: "carrying a motion back onto a skeleton",
                needed: 1,
                got: 0,
            });
        }
        let carriers = self.carriers_with(reference, mapped);
        let (p, c) = (reference.positions(), reference.confidence());
        let (q, qc) = (mapped.positions(), mapped.confidence());
        let (o, oc) = (output.positions(), output.confidence());
        let n = self.source.len();
        let mut pos = Array3::zeros((to, n, d));
        let mut conf = Array2::zeros((to, n));
        for (j, carrier) in carriers.iter().enumerate() {
            let a = match carrier {
                Carrier::Is(a) | Carrier::Moves(a) => Some(*a),
                Carrier::Held => None,
            };
            let last = (0..tr)
                .rev()
                .find(|&f| c[[f, j]] > 0.0 && a.is_none_or(|a| qc[[f, a]] > 0.0))
                .unwrap_or(tr - 1);
            for h in 0..to {
                let r = match pairing {
                    FramePairing::SameFrame => h,
                    FramePairing::LastFrame => last,
                };
                for k in 0..d {
                    let s = self.sign(k);
                    pos[[h, j, k]] = match (carrier, a) {
                        (Carrier::Is(_), Some(a)) => s * o[[h, a, k]],
                        (_, Some(a)) => p[[r, j, k]] + s * (o[[h, a, k]] - q[[r, a, k]]),
                        (_, None) => p[[r, j, k]],
                    };
                }
                conf[[h, j]] = match (carrier, a) {
                    (Carrier::Is(_), Some(a)) => oc[[h, a]],
                    (_, Some(a)) => oc[[h, a]].min(c[[r, j]]),
                    (_, None) => c[[r, j]],
                };
            }
        }
        Track::new(
            pos,
            Some(conf),
            output.fps(),
            output.units(),
            self.source.clone(),
        )
    }
}

/// How a source joint comes back from the target skeleton.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[non_exhaustive]
pub enum Carrier {
    /// The joint is target joint `a`.
    Is(usize),
    /// The joint moves rigidly with target joint `a`.
    Moves(usize),
    /// No target joint carries it: it is held.
    Held,
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::track::Units;

    /// A track of `skeleton` whose joint `j` sits at `(j, 2j, 3j)` plus
    /// `(f, 0, 0)` in frame `f` (the first `d` coordinates).
    fn ramp(skeleton: Skeleton, frames: usize, d: usize) -> Track {
        let j = skeleton.len();
        let pos = Array3::from_shape_fn((frames, j, d), |(f, a, k)| {
            (a * (k + 1)) as f64 + if k == 0 { f as f64 } else { 0.0 }
        });
        Track::new(pos, None, 30.0, Units::Metres, skeleton).unwrap()
    }

    fn close(a: f64, b: f64) -> bool {
        (a - b).abs() < 1e-9
    }

    #[test]
    fn coco17_to_penn13_selects_joints_with_the_nose_as_head() {
        let m = SkeletonMap::coco17_to_penn13().unwrap();
        let t = ramp(Skeleton::coco17(), 3, 2);
        let p = m.apply(&t).unwrap();
        assert_eq!(p.skeleton().name, "penn13");
        assert_eq!(p.point(1, 0).to_vec(), t.point(1, 0).to_vec());
        for (a, name) in p.skeleton().joints.iter().enumerate().skip(1) {
            let j = t.skeleton().joint_index(name).unwrap();
            assert_eq!(p.point(2, a).to_vec(), t.point(2, j).to_vec(), "{name}");
        }
    }

    #[test]
    fn blazepose_reaches_penn13_through_its_coco_joints() {
        let m = SkeletonMap::blazepose33_to_penn13().unwrap();
        let idx: Vec<usize> = m
            .sources()
            .iter()
            .map(|s| match s {
                JointSource::Joint(j) => *j,
                other => panic!("a selection expected, got {other:?}"),
            })
            .collect();
        assert_eq!(idx, vec![0, 11, 12, 13, 14, 15, 16, 23, 24, 25, 26, 27, 28]);
        let built = SkeletonMap::builtin(&Skeleton::blazepose33(), "penn13").unwrap();
        assert_eq!(built, m);
    }

    #[test]
    fn blazepose_world_to_msr20_derives_joints_and_turns_y_up() {
        let m = SkeletonMap::blazepose33_world_to_msr20().unwrap();
        let b = Skeleton::blazepose33();
        let mut t = ramp(b.clone(), 2, 3);
        t.confidence_mut()[[1, b.joint_index("left_hip").unwrap()]] = 0.25;
        let msr = m.apply(&t).unwrap();
        let s = Skeleton::msr20();
        let (lh, rh) = (
            b.joint_index("left_hip").unwrap(),
            b.joint_index("right_hip").unwrap(),
        );
        let hc = s.joint_index("hip_centre").unwrap();
        for k in 0..3 {
            let mean = 0.5 * (t.point(1, lh)[k] + t.point(1, rh)[k]);
            let sign = if k == 1 { -1.0 } else { 1.0 };
            assert!(close(msr.point(1, hc)[k], sign * mean));
        }
        // a derived joint is as confident as its least confident source
        assert!(close(msr.confidence()[[1, hc]], 0.25));
        assert!(close(msr.confidence()[[0, hc]], 1.0));
        let ls = s.joint_index("left_shoulder").unwrap();
        let bls = b.joint_index("left_shoulder").unwrap();
        assert!(close(msr.point(0, ls)[1], -t.point(0, bls)[1]));
        // 2D pixels are refused: the derived joints and axes need world landmarks
        let flat = ramp(b, 2, 2);
        let e = m.apply(&flat).unwrap_err().to_string();
        assert!(e.contains("3D"), "{e}");
    }

    #[test]
    fn carrying_back_a_mapped_track_gives_the_input_back() {
        let m = SkeletonMap::blazepose33_world_to_msr20().unwrap();
        let t = ramp(Skeleton::blazepose33(), 4, 3);
        let back = m
            .carry_back(&t, &m.apply(&t).unwrap(), FramePairing::SameFrame)
            .unwrap();
        assert_eq!(back.skeleton().name, "blazepose33");
        for (x, y) in back.positions().iter().zip(t.positions().iter()) {
            assert!(close(*x, *y));
        }
    }

    #[test]
    fn unpredicted_joints_move_rigidly_with_their_carrier() {
        let m = SkeletonMap::coco17_to_penn13().unwrap();
        let past = ramp(Skeleton::coco17(), 5, 2);
        // a "forecast": the last mapped pose moved by (10, −4), two frames
        let last = m.apply(&past.slice_frames(4, 5).unwrap()).unwrap();
        let mut out = Array3::zeros((2, 13, 2));
        for h in 0..2 {
            for a in 0..13 {
                out[[h, a, 0]] = last.point(0, a)[0] + 10.0;
                out[[h, a, 1]] = last.point(0, a)[1] - 4.0;
            }
        }
        let out = Track::new(out, None, 30.0, Units::Metres, Skeleton::penn13()).unwrap();
        let back = m.carry_back(&past, &out, FramePairing::LastFrame).unwrap();
        assert_eq!(back.n_frames(), 2);
        for j in 0..17 {
            assert!(close(back.point(1, j)[0], past.point(4, j)[0] + 10.0));
            assert!(close(back.point(1, j)[1], past.point(4, j)[1] - 4.0));
        }
        // the eyes and ears are carried by the nearest predicted joint; the nose is the head
        let carriers = m.carriers(&past).unwrap();
        assert_eq!(carriers[0], Carrier::Is(0));
        assert!(carriers[1..5]
            .iter()
            .all(|c| matches!(c, Carrier::Moves(_))));
    }

    #[test]
    fn a_joint_never_seen_is_held() {
        let m = SkeletonMap::coco17_to_penn13().unwrap();
        let mut past = ramp(Skeleton::coco17(), 3, 2);
        past.confidence_mut().column_mut(3).fill(0.0); // left ear never seen
        let out = m.apply(&past).unwrap();
        let carriers = m.carriers(&past).unwrap();
        assert_eq!(carriers[3], Carrier::Held);
        let back = m.carry_back(&past, &out, FramePairing::SameFrame).unwrap();
        assert_eq!(back.confidence()[[2, 3]], 0.0);
        assert!(back.positions().iter().all(|v| v.is_finite()));
    }

    #[test]
    fn bad_maps_are_refused() {
        let (c, p) = (Skeleton::coco17(), Skeleton::penn13());
        assert!(SkeletonMap::new(c.clone(), p.clone(), vec![], [1.0; 3]).is_err());
        let mut s: Vec<JointSource> = (0..13).map(JointSource::Joint).collect();
        s[0] = JointSource::Blend(vec![(0, 0.5), (1, 0.4)]);
        assert!(SkeletonMap::new(c.clone(), p.clone(), s.clone(), [1.0; 3]).is_err());
        s[0] = JointSource::Joint(40);
        assert!(SkeletonMap::new(c.clone(), p.clone(), s, [1.0; 3]).is_err());
        let ok: Vec<JointSource> = (0..13).map(JointSource::Joint).collect();
        assert!(SkeletonMap::new(c.clone(), p, ok, [1.0, 2.0, 1.0]).is_err());
        let e = SkeletonMap::builtin(&Skeleton::msr20(), "penn13")
            .unwrap_err()
            .to_string();
        assert!(e.contains("no mapping"), "{e}");
        // a track of another skeleton is refused
        let m = SkeletonMap::coco17_to_penn13().unwrap();
        assert!(m.apply(&ramp(Skeleton::penn13(), 2, 2)).is_err());
        assert_eq!(
            SkeletonMap::builtin(&c, "coco17").unwrap(),
            SkeletonMap::identity(&c)
        );
    }
}
