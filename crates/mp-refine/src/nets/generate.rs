//! Motion from the generator network: action-conditioned clips in the
//! networks' canonical features.

use ndarray::Array3;
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, StandardNormal};

use super::{RefineNets, N_ACTIONS};
use crate::error::{RefineError, Result};
use crate::motion::{FRAME_FEATURES, NET_FRAMES};

/// Clips from the generator: `per_action` per action 1..=20, latents drawn
/// from `ChaCha8Rng::seed_from_u64(seed)`. Returns `N × 60 × 60` features and labels.
pub fn generate_clips(
    nets: &RefineNets,
    per_action: usize,
    seed: u64,
) -> Result<(Array3<f32>, Vec<u32>)> {
    let zg = nets.sizes().generator_latent;
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let n = per_action * N_ACTIONS;
    let mut out = Array3::<f32>::zeros((n, NET_FRAMES, FRAME_FEATURES));
    let mut labels = Vec::with_capacity(n);
    for a in 0..N_ACTIONS {
        let mut onehot = vec![0f32; per_action * N_ACTIONS];
        for r in 0..per_action {
            onehot[r * N_ACTIONS + a] = 1.0;
        }
        let z: Vec<f32> = (0..per_action * zg)
            .map(|_| StandardNormal.sample(&mut rng))
            .collect();
        let m = nets.generate_motion(&onehot, &z)?;
        if m.iter().any(|v| !v.is_finite()) {
            return Err(RefineError::NonFinite(format!(
                "generator: non-finite motion for action {}",
                a + 1
            )));
        }
        let arr = Array3::from_shape_vec((per_action, NET_FRAMES, FRAME_FEATURES), m)
            .map_err(|e| RefineError::Shape(e.to_string()))?;
        out.slice_mut(ndarray::s![a * per_action..(a + 1) * per_action, .., ..])
            .assign(&arr);
        labels.extend(std::iter::repeat_n(a as u32 + 1, per_action));
    }
    Ok((out, labels))
}
