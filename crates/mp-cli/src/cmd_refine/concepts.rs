//! `mp concepts`: anchor concepts (clusters + quality model) from MSR
//! Action3D or a folder of tracks.

use std::path::{Path, PathBuf};

use anyhow::{bail, Context};
use clap::{Args, ValueEnum};
use mp_geom::MsrAction3D;
use mp_refine::Linkage;
use mp_refine::{canonical_anchor_samples, msr_anchor_samples, msr_training_clips};
use mp_refine::{learn_concepts, ClusterMethod, ConceptParams, SegmentParams};
use mp_refine::{DEFAULT_BVH_LENGTH_SCALE, HIP_CENTRE};

use super::folder_track;

/// Clustering algorithm of `mp concepts`.
#[derive(ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
pub enum Method {
    /// K-means (L2).
    Kmeans,
    /// DBSCAN.
    Dbscan,
    /// OPTICS, cut at --tolerance (ordering radius --optics-radius).
    Optics,
    /// Agglomerative hierarchical clustering into --clusters concepts (--linkage).
    Hierarchical,
}

/// Linkage of `mp concepts --method hierarchical`.
#[derive(ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
pub enum LinkageArg {
    /// Ward's minimum variance.
    Ward,
    /// Mean pairwise distance.
    Average,
    /// Largest pairwise distance.
    Complete,
    /// Smallest pairwise distance.
    Single,
}

impl From<LinkageArg> for Linkage {
    fn from(l: LinkageArg) -> Self {
        match l {
            LinkageArg::Ward => Linkage::Ward,
            LinkageArg::Average => Linkage::Average,
            LinkageArg::Complete => Linkage::Complete,
            LinkageArg::Single => Linkage::Single,
        }
    }
}

/// Arguments of `mp concepts`.
#[derive(Args, Debug)]
pub struct ConceptsArgs {
    /// MSR Action3D npz, or a folder of 20-joint tracks / CMU BVH files.
    pub data: PathBuf,
    /// Output concepts JSON.
    #[arg(short, long)]
    pub output: PathBuf,
    /// Clustering algorithm.
    #[arg(long, value_enum, default_value = ConceptParams::default().method.name())]
    pub method: Method,
    /// Concepts per action (k-means, hierarchical).
    #[arg(long, default_value_t = ClusterMethod::DEFAULT_CLUSTERS)]
    pub clusters: usize,
    /// Neighbourhood radius (DBSCAN; the cut of OPTICS; scale-normalised feature units).
    #[arg(long, default_value_t = ClusterMethod::DEFAULT_TOLERANCE)]
    pub tolerance: f64,
    /// Largest radius of the OPTICS ordering (≥ --tolerance).
    #[arg(long, default_value_t = ClusterMethod::DEFAULT_OPTICS_RADIUS)]
    pub optics_radius: f64,
    /// Points of a DBSCAN / OPTICS core.
    #[arg(long, default_value_t = ClusterMethod::DEFAULT_MIN_POINTS)]
    pub min_points: usize,
    /// Linkage of hierarchical clustering.
    #[arg(long, value_enum, default_value = Linkage::default().as_str())]
    pub linkage: LinkageArg,
    /// Subjects of an MSR npz to use (comma separated; default: all but 9, the held-out subject).
    #[arg(long, value_delimiter = ',')]
    pub subjects: Option<Vec<u32>>,
    /// Action of every track of a folder.
    #[arg(long, default_value_t = 1)]
    pub action: u32,
    /// Segmentation penalty λ (mm).
    #[arg(long, default_value_t = SegmentParams::default().lambda)]
    pub lambda: f64,
    /// BVH length unit → metres.
    #[arg(long, default_value_t = DEFAULT_BVH_LENGTH_SCALE)]
    pub bvh_scale: f64,
    /// Seed.
    #[arg(long, default_value_t = ConceptParams::default().seed)]
    pub seed: u64,
}

/// Whether `p` names a track file (by extension).
fn is_track_file(p: &Path) -> bool {
    p.extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase)
        .is_some_and(|e| mp_geom::TRACK_EXTENSIONS.contains(&e.as_str()))
}

/// `mp concepts`.
pub fn concepts_cmd(a: &ConceptsArgs) -> anyhow::Result<()> {
    let method = match a.method {
        Method::Kmeans => ClusterMethod::kmeans(a.clusters),
        Method::Dbscan => ClusterMethod::Dbscan {
            min_points: a.min_points,
            tolerance: a.tolerance,
        },
        Method::Optics => ClusterMethod::Optics {
            min_points: a.min_points,
            tolerance: a.optics_radius,
            cut: a.tolerance,
        },
        Method::Hierarchical => ClusterMethod::Hierarchical {
            n_clusters: a.clusters,
            linkage: a.linkage.into(),
        },
    };
    let params = ConceptParams {
        method,
        root_joint: Some(HIP_CENTRE),
        seed: a.seed,
        ..ConceptParams::default()
    };
    params.validate()?;
    let seg = SegmentParams {
        lambda: a.lambda,
        ..SegmentParams::default()
    };
    let samples = if a.data.is_dir() {
        let mut files: Vec<PathBuf> = std::fs::read_dir(&a.data)
            .with_context(|| format!("listing {}", a.data.display()))?
            .filter_map(|e| e.ok().map(|e| e.path()))
            .filter(|p| p.is_file() && is_track_file(p))
            .collect();
        files.sort();
        if files.is_empty() {
            bail!("{}: no track or BVH file", a.data.display());
        }
        let mut out = Vec::new();
        for f in &files {
            let t =
                folder_track(f, a.bvh_scale).with_context(|| format!("reading {}", f.display()))?;
            out.extend(
                canonical_anchor_samples(&t, a.action, &seg, &params)
                    .with_context(|| format!("anchors of {}", f.display()))?,
            );
        }
        println!("{} files, {} anchors", files.len(), out.len());
        out
    } else {
        let data = MsrAction3D::open(&a.data).with_context(|| {
            format!(
                "reading {} as an MSR Action3D npz (pass a folder for single tracks)",
                a.data.display()
            )
        })?;
        let idx = msr_training_clips(&data, a.subjects.as_deref());
        let s = msr_anchor_samples(&data, &idx, &seg, &params)?;
        println!("{} clips, {} anchors", idx.len(), s.len());
        s
    };
    let concepts = learn_concepts(&samples, &params)?;
    for (act, ac) in &concepts.actions {
        let noise = ac.labels.iter().filter(|l| l.is_none()).count();
        println!(
            "action {act:>2}: {} concepts from {} anchors{}, flaw threshold {:.2}",
            ac.centroids.len(),
            ac.labels.len(),
            if noise > 0 {
                format!(" ({noise} noise)")
            } else {
                String::new()
            },
            ac.score_threshold
        );
    }
    mp_geom::write_atomic(&a.output, concepts.to_json()?.as_bytes())
        .with_context(|| format!("writing {}", a.output.display()))?;
    Ok(())
}
