//! The hierarchy of an exported BVH: the most rigid spanning tree of the
//! skeleton's bones.

use super::fill::point;
use crate::skeleton::Skeleton;
use crate::stats::median;
use crate::track::Track;

/// The hierarchy of a skeleton as a tree over its joints.
pub(super) struct Tree {
    pub root: usize,
    pub parent: Vec<Option<usize>>,
    pub children: Vec<Vec<usize>>,
}

pub(super) fn neighbours(sk: &Skeleton) -> Vec<Vec<usize>> {
    let n = sk.len();
    let mut nb = vec![Vec::new(); n];
    for &(a, b) in &sk.bones {
        if a < n && b < n && a != b {
            if !nb[a].contains(&b) {
                nb[a].push(b);
            }
            if !nb[b].contains(&a) {
                nb[b].push(a);
            }
        }
    }
    for l in &mut nb {
        l.sort_unstable();
    }
    nb
}

/// Breadth-first distances from `start` (`usize::MAX` where unreachable).
fn distances(nb: &[Vec<usize>], start: usize) -> Vec<usize> {
    let mut dist = vec![usize::MAX; nb.len()];
    let mut queue = std::collections::VecDeque::from([start]);
    dist[start] = 0;
    while let Some(i) = queue.pop_front() {
        for &k in &nb[i] {
            if dist[k] == usize::MAX {
                dist[k] = dist[i] + 1;
                queue.push_back(k);
            }
        }
    }
    dist
}

/// How much the distance between joints `a` and `b` changes: the median
/// absolute deviation of their distance over `frames` where both were
/// found (infinite where never both).
fn length_spread(track: &Track, a: usize, b: usize, frames: &[usize]) -> f64 {
    let mut l: Vec<f64> = frames
        .iter()
        .filter(|&&t| track.is_valid(t, a, 0.0) && track.is_valid(t, b, 0.0))
        .map(|&t| (point(track, t, a) - point(track, t, b)).length())
        .collect();
    let Some(m) = median(&mut l) else {
        return f64::INFINITY;
    };
    let mut dev: Vec<f64> = l.iter().map(|x| (x - m).abs()).collect();
    median(&mut dev).unwrap_or(f64::INFINITY)
}

fn find(up: &mut [usize], i: usize) -> usize {
    let mut r = i;
    while up[r] != r {
        r = up[r];
    }
    let mut k = i;
    while up[k] != r {
        let next = up[k];
        up[k] = r;
        k = next;
    }
    r
}

/// Kruskal: adds `edges` (spread, a, b) from the most rigid on, each that
/// joins two parts.
fn join(edges: &mut [(f64, usize, usize)], up: &mut [usize], adj: &mut [Vec<usize>]) {
    edges.sort_by(|x, y| x.0.total_cmp(&y.0));
    for &(_, a, b) in edges.iter() {
        let (ra, rb) = (find(up, a), find(up, b));
        if ra != rb {
            up[ra] = rb;
            adj[a].push(b);
            adj[b].push(a);
        }
    }
}

impl Tree {
    /// The most rigid tree over the skeleton's bones (see the module docs).
    pub fn of(track: &Track) -> Tree {
        let sk = track.skeleton();
        let n = sk.len();
        // At most 600 frames, evenly spaced, measure rigidity.
        let step = track.n_frames().div_ceil(600).max(1);
        let frames: Vec<usize> = (0..track.n_frames()).step_by(step).collect();
        let mut up: Vec<usize> = (0..n).collect();
        let mut adj = vec![Vec::new(); n];
        let mut bones: Vec<(f64, usize, usize)> = neighbours(sk)
            .iter()
            .enumerate()
            .flat_map(|(a, l)| l.iter().filter(move |&&b| a < b).map(move |&b| (a, b)))
            .map(|(a, b)| (length_spread(track, a, b, &frames), a, b))
            .collect();
        join(&mut bones, &mut up, &mut adj);
        // Parts no bone joins: by the most rigid pair of joints between them.
        let part: Vec<usize> = (0..n).map(|i| find(&mut up, i)).collect();
        if part.iter().any(|&p| p != part[0]) {
            let mut pairs = Vec::new();
            for a in 0..n {
                for b in a + 1..n {
                    if part[a] != part[b] {
                        pairs.push((length_spread(track, a, b, &frames), a, b));
                    }
                }
            }
            join(&mut pairs, &mut up, &mut adj);
        }
        for l in &mut adj {
            l.sort_unstable();
        }
        // The root: the skeleton's, else the centre of the tree (fewest
        // bones to the farthest joint, then most bones, then lowest index),
        // which keeps the chains, along which errors add up, shortest.
        let root = sk.root.filter(|&r| r < n).unwrap_or_else(|| {
            (0..n)
                .min_by_key(|&i| {
                    let ecc = distances(&adj, i).into_iter().max().unwrap_or(0);
                    (ecc, std::cmp::Reverse(adj[i].len()), i)
                })
                .unwrap_or(0)
        });
        let mut parent = vec![None; n];
        let mut seen = vec![false; n];
        let mut queue = std::collections::VecDeque::from([root]);
        seen[root] = true;
        while let Some(i) = queue.pop_front() {
            for &k in &adj[i] {
                if !seen[k] {
                    seen[k] = true;
                    parent[k] = Some(i);
                    queue.push_back(k);
                }
            }
        }
        let mut children = vec![Vec::new(); n];
        for (i, p) in parent.iter().enumerate() {
            if let Some(p) = p {
                children[*p].push(i);
            }
        }
        Tree {
            root,
            parent,
            children,
        }
    }
}
