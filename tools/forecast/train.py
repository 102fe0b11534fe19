#!/usr/bin/env python3
"""Train the keypoint forecasting models of `mp-forecast` and export them to ONNX.

Two models, both causal temporal convolutional networks on normalised keypoints:

* ``latent`` ("AR on Φ"): a causal temporal encoder maps every frame to a
  latent; an autoregressive causal model of the same shape predicts the next
  latent; a read-out maps a latent to a pose.
* ``pose`` ("AR on Θ", the ablation): the same autoregressive architecture
  directly on poses.

Every causal network is 3 residual blocks of GroupNorm-ReLU-Conv1d(k=3)-GroupNorm-ReLU-Conv1d(k=3)
with edge (replicate) padding on the left only, so the output at frame t depends on frames
t-12..t (receptive field 13). GroupNorm normalises the channel groups of each frame on
its own (no statistics over time, which would leak the future).

Input normalisation (identical in `crates/mp-forecast/src/normalize.rs`), per window, from the
context frames only:

* root of a frame = mean of its valid hip joints (`left_hip`, `right_hip`);
* anchor = root of the latest context frame that has one (else the mean of the valid joints of
  the latest frame that has any);
* scale = median over the context frames of the torso length |mid-shoulders - root| (frames
  with a valid shoulder and hip); if no frame has one, a third of the largest side of the
  bounding box of all valid context joints;
* a valid joint becomes (p - anchor) / scale; a missing joint becomes 0 with mask 0.

A frame's feature vector is ``[coords (J*D, joint-major), mask (J)]``.

Training: windows of 15 context + 25 future frames; teacher forcing on every frame, then a
curriculum that rolls the autoregressive model on its own predictions for K steps after the
context, K growing from 1 to 25. Masked L1 loss in normalised units. Seeded. Model selection by
validation PCK@0.05 (after the optimal scale + translation per frame) of a 30-step rollout, on the
validation clips (every 10th clip of the file, index % 10 == 0).
"""

import argparse
import hashlib
import json
import math
import os
import sys
import time

import numpy as np
import torch
import torch.nn as nn
import torch.nn.functional as F

CONTEXT = 15
FUTURE = 25
RF = 13
EVAL_HORIZON = 30
VAL_EVERY = 10

PENN_JOINTS = ["head", "left_shoulder", "right_shoulder", "left_elbow", "right_elbow",
               "left_wrist", "right_wrist", "left_hip", "right_hip", "left_knee",
               "right_knee", "left_ankle", "right_ankle"]
MSR_JOINTS = ["right_shoulder", "left_shoulder", "neck", "spine", "right_hip", "left_hip",
              "hip_centre", "right_elbow", "left_elbow", "right_wrist", "left_wrist",
              "right_hand", "left_hand", "right_knee", "left_knee", "right_ankle",
              "left_ankle", "right_foot", "left_foot", "head"]


# ----------------------------------------------------------------------------- data

def load_dataset(path):
    z = np.load(path, allow_pickle=False)
    if "keypoints" in z.files:
        pos = z["keypoints"].astype(np.float64)
        vis = z["visibility"].astype(np.float64) > 0
        names = PENN_JOINTS
        kind = "penn_action"
    elif "joints" in z.files:
        pos = z["joints"].astype(np.float64)
        vis = z["conf"].astype(np.float64) > 0
        names = MSR_JOINTS
        kind = "msr_action3d"
    else:
        raise SystemExit(f"{path}: neither `keypoints` (Penn Action) nor `joints` (MSR Action3D)")
    vis &= np.isfinite(pos).all(axis=-1)
    pos = np.where(np.isfinite(pos), pos, 0.0)
    off = z["offsets"].astype(np.int64)
    action = [str(a) for a in z["action"]]
    clips = [(pos[off[i]:off[i + 1]], vis[off[i]:off[i + 1]]) for i in range(len(off) - 1)]
    return kind, names, clips, action


def pairs(names):
    idx = {n: i for i, n in enumerate(names)}
    hips = [idx[n] for n in ("left_hip", "right_hip") if n in idx]
    shoulders = [idx[n] for n in ("left_shoulder", "right_shoulder") if n in idx]
    flip = list(range(len(names)))
    for i, n in enumerate(names):
        for a, b in (("left_", "right_"), ("right_", "left_")):
            if n.startswith(a) and (b + n[len(a):]) in idx:
                flip[i] = idx[b + n[len(a):]]
    return hips, shoulders, flip


def mean_valid(p, v, joints):
    """p (T,J,D), v (T,J) -> (T,D) mean over the valid `joints`, and (T,) whether any."""
    if not joints:
        return np.zeros(p.shape[::2]), np.zeros(p.shape[0], bool)
    pj = p[:, joints]
    vj = v[:, joints].astype(np.float64)
    n = vj.sum(1)
    m = (pj * vj[..., None]).sum(1) / np.maximum(n, 1)[:, None]
    return m, n > 0


def normalizer(p, v, hips, shoulders):
    """Anchor (D,) and scale from context frames p (T,J,D), v (T,J); None when nothing is valid."""
    root, has_root = mean_valid(p, v, hips)
    anchor = None
    for t in range(p.shape[0] - 1, -1, -1):
        if has_root[t]:
            anchor = root[t]
            break
    if anchor is None:
        for t in range(p.shape[0] - 1, -1, -1):
            if v[t].any():
                anchor = p[t][v[t]].mean(0)
                break
    if anchor is None:
        return None
    sh, has_sh = mean_valid(p, v, shoulders)
    ok = has_sh & has_root
    scale = float(np.median(np.linalg.norm(sh[ok] - root[ok], axis=-1))) if ok.any() else 0.0
    if not scale > 1e-9:
        pts = p[v]
        scale = float((pts.max(0) - pts.min(0)).max()) / 3.0
    if not scale > 1e-9:
        return None
    return anchor, scale


def features(p, v, anchor, scale):
    """(T,J,D),(T,J) -> (T, J*D + J) float32."""
    x = np.where(v[..., None], (p - anchor) / scale, 0.0)
    t = p.shape[0]
    return np.concatenate([x.reshape(t, -1), v.astype(np.float64)], 1).astype(np.float32)


def make_windows(clips, indices, hips, shoulders, stride):
    """Windows of CONTEXT + FUTURE frames: features, targets, target masks, future length."""
    feats, targ, tmask = [], [], []
    length = CONTEXT + FUTURE
    for ci in indices:
        p, v = clips[ci]
        T = p.shape[0]
        for s in range(0, T - CONTEXT, stride):
            n = normalizer(p[s:s + CONTEXT], v[s:s + CONTEXT], hips, shoulders)
            if n is None:
                continue
            e = min(T, s + length)
            pp = p[s:e]
            vv = v[s:e]
            if e - s < length:
                pad = length - (e - s)
                pp = np.concatenate([pp, np.repeat(pp[-1:], pad, 0)], 0)
                vv = np.concatenate([vv, np.zeros((pad, vv.shape[1]), bool)], 0)
            f = features(pp, vv, *n)
            feats.append(f)
            targ.append(f[:, : p.shape[1] * p.shape[2]])
            tmask.append(vv.astype(np.float32))
    return (torch.from_numpy(np.stack(feats)), torch.from_numpy(np.stack(targ)),
            torch.from_numpy(np.stack(tmask)))


# ----------------------------------------------------------------------------- model

class FrameGroupNorm(nn.Module):
    """GroupNorm over the channel groups of each frame separately: x (B, T, C)."""

    def __init__(self, groups, channels):
        super().__init__()
        self.groups = groups
        self.weight = nn.Parameter(torch.ones(channels))
        self.bias = nn.Parameter(torch.zeros(channels))

    def forward(self, x):
        b, t, c = x.shape
        g = x.reshape(b, t, self.groups, c // self.groups)
        mean = g.mean(-1, keepdim=True)
        var = ((g - mean) ** 2).mean(-1, keepdim=True)
        g = (g - mean) / torch.sqrt(var + 1e-5)
        return g.reshape(b, t, c) * self.weight + self.bias


class CausalConv(nn.Module):
    """Conv1d(k=3) with 2 frames of edge padding on the left: x (B, T, C) -> (B, T, C)."""

    def __init__(self, channels):
        super().__init__()
        self.conv = nn.Conv1d(channels, channels, 3)

    def forward(self, x, pad=True):
        h = x.transpose(1, 2)
        if pad:
            h = torch.cat([h[:, :, :1], h[:, :, :1], h], 2)
        return self.conv(h).transpose(1, 2)


class Block(nn.Module):
    def __init__(self, channels, groups):
        super().__init__()
        self.n1 = FrameGroupNorm(groups, channels)
        self.c1 = CausalConv(channels)
        self.n2 = FrameGroupNorm(groups, channels)
        self.c2 = CausalConv(channels)

    def forward(self, x, pad=True):
        h = self.c1(F.relu(self.n1(x)), pad)
        h = self.c2(F.relu(self.n2(h)), pad)
        return x + h if pad else x[:, 4:] + h


class Causal(nn.Module):
    """Linear in -> 3 residual blocks (receptive field 13) -> linear out."""

    def __init__(self, n_in, channels, n_out, groups, blocks=3):
        super().__init__()
        self.inp = nn.Linear(n_in, channels)
        self.blocks = nn.ModuleList([Block(channels, groups) for _ in range(blocks)])
        self.norm = FrameGroupNorm(groups, channels)
        self.out = nn.Linear(channels, n_out)

    def forward(self, x, pad=True):
        """pad=True: output per input frame (edge padding); pad=False: x must hold exactly
        the receptive field (13 frames) and the output is the last frame's only (B, 1, n_out),
        identical to the padded output at that frame."""
        h = self.inp(x)
        for b in self.blocks:
            h = b(h, pad)
        return self.out(F.relu(self.norm(h)))

    def zero_output(self):
        nn.init.zeros_(self.out.weight)
        nn.init.zeros_(self.out.bias)


class Readout(nn.Module):
    """Latent -> pose: a linear map plus a residual MLP (whose last layer starts at zero)."""

    def __init__(self, channels, n_pose):
        super().__init__()
        self.lin = nn.Linear(channels, n_pose)
        self.mlp = nn.Sequential(nn.Linear(channels, channels), nn.ReLU(), nn.Linear(channels, n_pose))
        nn.init.zeros_(self.mlp[2].weight)
        nn.init.zeros_(self.mlp[2].bias)

    def forward(self, lat):
        return self.lin(lat) + self.mlp(lat)


class LatentModel(nn.Module):
    def __init__(self, n_feat, n_pose, channels, groups):
        super().__init__()
        self.encoder = Causal(n_feat, channels, channels, groups)
        self.ar = Causal(channels, channels, channels, groups)
        self.ar.zero_output()
        self.readout = Readout(channels, n_pose)

    def encode(self, x):
        return self.encoder(x)

    def step(self, lat):
        """lat (B, RF, C) -> next latent (B, C) (residual on the last latent)."""
        return lat[:, -1] + self.ar(lat, pad=False)[:, -1]

    def step_all(self, lat):
        """Teacher forcing: prediction of frame t+1 from frames <= t, for every t."""
        return lat + self.ar(lat)


class PoseModel(nn.Module):
    def __init__(self, n_feat, n_pose, channels, groups):
        super().__init__()
        self.n_pose = n_pose
        self.ar = Causal(n_feat, channels, n_pose, groups)
        self.ar.zero_output()

    def step(self, x):
        return x[:, -1, : self.n_pose] + self.ar(x, pad=False)[:, -1]

    def step_all(self, x):
        return x[..., : self.n_pose] + self.ar(x)


class EncoderExport(nn.Module):
    def __init__(self, m):
        super().__init__()
        self.m = m

    def forward(self, frames):
        lat = self.m.encode(frames)
        return lat, self.m.readout(lat)


class ArStepExport(nn.Module):
    def __init__(self, m):
        super().__init__()
        self.m = m

    def forward(self, latents):
        nxt = self.m.step(latents)
        return nxt, self.m.readout(nxt)


class PoseStepExport(nn.Module):
    def __init__(self, m):
        super().__init__()
        self.m = m

    def forward(self, frames):
        return self.m.step(frames)


# ----------------------------------------------------------------------------- training

def masked_l1(pred, target, mask, dims):
    """pred/target (..., J*D), mask (..., J)."""
    b = pred.shape[:-1]
    e = (pred - target).abs().reshape(*b, -1, dims).sum(-1)
    return (e * mask).sum() / mask.sum().clamp(min=1.0)


def as_features(pose, n_joints):
    """Predicted pose (B, J*D) -> feature row (B, F) with every joint valid."""
    return torch.cat([pose, torch.ones(pose.shape[0], n_joints, dtype=pose.dtype)], 1)


def anchored(obs, obs_mask, r_pred, r_obs, dims):
    """Anchored read-out: observed pose + R(predicted latent) - R(latent of the observed frame),
    for the joints valid in the observed frame; the plain read-out elsewhere. obs/r_* (..., J*D),
    obs_mask (..., J). Identical to `ArParams::anchored_readout` in `crates/mp-forecast`."""
    valid = (obs_mask > 0.5).repeat_interleave(dims, -1)
    return torch.where(valid, obs + r_pred - r_obs, r_pred)


def rollout_latent(model, x, steps, n_pose, dims, anchor=True):
    """x (B, CONTEXT(+), F) -> predicted poses (B, steps, P) (anchored read-out unless
    anchor=False), latents (B, steps, C)."""
    lat = model.encode(x[:, :CONTEXT])
    last = x[:, CONTEXT - 1]
    obs, obs_mask = last[:, :n_pose], last[:, n_pose:]
    r_obs = model.readout(lat[:, -1])
    seq = lat
    poses, lats = [], []
    for _ in range(steps):
        nxt = model.step(seq[:, -RF:])
        lats.append(nxt)
        r = model.readout(nxt)
        poses.append(anchored(obs, obs_mask, r, r_obs, dims) if anchor else r)
        seq = torch.cat([seq, nxt[:, None]], 1)
    return torch.stack(poses, 1), torch.stack(lats, 1)


def rollout_pose(model, x, steps, n_joints):
    seq = x[:, :CONTEXT]
    poses = []
    for _ in range(steps):
        nxt = model.step(seq[:, -RF:])
        poses.append(nxt)
        seq = torch.cat([seq, as_features(nxt, n_joints)[:, None]], 1)
    return torch.stack(poses, 1)


def pck_frames(pred, gt, vis, dims, alpha=0.05, min_visible=6):
    """PCK per frame (percent, NaN when < min_visible): arrays (N, J*D), (N, J*D), (N, J)."""
    n = pred.shape[0]
    p = pred.reshape(n, -1, dims).astype(np.float64)
    g = gt.reshape(n, -1, dims).astype(np.float64)
    v = vis > 0
    out = np.full(n, np.nan)
    for i in range(n):
        vi = v[i]
        k = vi.sum()
        if k < min_visible:
            continue
        pi, gi = p[i][vi], g[i][vi]
        pm, gm = pi.mean(0), gi.mean(0)
        pc, gc = pi - pm, gi - gm
        pp = (pc * pc).sum()
        s = (pc * gc).sum() / pp if pp > 0 else 1.0
        err = np.linalg.norm(s * pc + gm - gi, axis=-1)
        size = (gi.max(0) - gi.min(0)).max()
        out[i] = 100.0 * (err <= alpha * size).sum() / k
    return out


def validate(kind, model, val, n_joints, dims, horizons):
    x, y, m = val
    model.eval()
    res = {}
    with torch.no_grad():
        preds = []
        for i in range(0, x.shape[0], 512):
            xb = x[i:i + 512]
            if kind == "latent":
                p, _ = rollout_latent(model, xb, EVAL_HORIZON, x.shape[-1] - n_joints, dims)
            else:
                p = rollout_pose(model, xb, EVAL_HORIZON, n_joints)
            preds.append(p)
        pred = torch.cat(preds).numpy()
    model.train()
    for h in horizons:
        t = CONTEXT + h - 1
        if t >= y.shape[1]:
            continue
        vals = pck_frames(pred[:, h - 1], y[:, t].numpy(), m[:, t].numpy(), dims)
        res[f"h{h}"] = float(np.nanmean(vals))
    return res


def train_one(kind, args, train, val, n_feat, n_pose, n_joints, dims, flip):
    torch.manual_seed(args.seed + (0 if kind == "latent" else 1))
    rng = np.random.default_rng(args.seed + (0 if kind == "latent" else 1))
    cls = LatentModel if kind == "latent" else PoseModel
    model = cls(n_feat, n_pose, args.channels, args.groups)
    opt = torch.optim.Adam(model.parameters(), lr=args.lr)
    epochs = args.epochs if kind == "latent" else args.pose_epochs
    pre = args.pretrain_epochs if kind == "latent" else 0
    # curriculum: teacher forcing only (K = 0) while pre-training, then own-prediction
    # steps K = 1 -> FUTURE over the first 70 % of the curriculum epochs
    ramp = max(1, int(0.7 * epochs))
    schedule = [0] * pre + [int(round(1 + min(1.0, e / max(1, ramp - 1)) * (FUTURE - 1)))
                            for e in range(epochs)]
    epochs = len(schedule)
    total_steps = sum(math.ceil(min(args.samples_per_epoch * (args.pretrain_factor if k == 0 else 1),
                                    train[0].shape[0]) / args.batch) for k in schedule)
    sched = torch.optim.lr_scheduler.OneCycleLR(opt, max_lr=args.lr, total_steps=total_steps,
                                                pct_start=0.1)
    x_all, y_all, m_all = train
    n = x_all.shape[0]
    flip_idx = torch.tensor(flip)
    best, best_state, history = -1.0, None, []
    t0 = time.time()
    for ep in range(epochs):
        k = schedule[ep]
        per_epoch = args.samples_per_epoch * (args.pretrain_factor if k == 0 else 1)
        order = rng.permutation(n)[:per_epoch]
        losses = []
        for bi in range(0, len(order), args.batch):
            idx = torch.from_numpy(order[bi:bi + args.batch])
            x, y, m = x_all[idx], y_all[idx], m_all[idx]
            if rng.random() < 0.5:  # left/right mirror in normalised space
                b, t, _ = x.shape
                c = x[..., :n_pose].reshape(b, t, n_joints, dims)[:, :, flip_idx].clone()
                c[..., 0] = -c[..., 0]
                mm = x[..., n_pose:][:, :, flip_idx]
                x = torch.cat([c.reshape(b, t, -1), mm], -1)
                y = x[..., :n_pose]
                m = m[:, :, flip_idx]
            if kind == "latent":
                lat = model.encode(x)
                r_lat = model.readout(lat)
                rec = masked_l1(r_lat, y, m, dims)
                nxt = model.step_all(lat)[:, :-1]
                r_nxt = model.readout(nxt)
                # next frame decoded relative to the frame it is predicted from
                tf = masked_l1(anchored(y[:, :-1], m[:, :-1], r_nxt, r_lat[:, :-1], dims),
                               y[:, 1:], m[:, 1:], dims)
                tf_lat = (nxt - lat[:, 1:].detach()).abs().mean()
                seq = lat[:, :CONTEXT]
                roll, roll_lat = 0.0, 0.0
                obs, obs_mask, r_obs = y[:, CONTEXT - 1], m[:, CONTEXT - 1], r_lat[:, CONTEXT - 1]
                for s in range(k):
                    nl = model.step(seq[:, -RF:])
                    roll = roll + masked_l1(anchored(obs, obs_mask, model.readout(nl), r_obs, dims),
                                            y[:, CONTEXT + s], m[:, CONTEXT + s], dims)
                    roll_lat = roll_lat + (nl - lat[:, CONTEXT + s].detach()).abs().mean()
                    seq = torch.cat([seq, nl[:, None]], 1)
                loss = rec + tf + args.latent_weight * tf_lat
                if k > 0:
                    loss = loss + (roll + args.latent_weight * roll_lat) / k
            else:
                nxt = model.step_all(x)[:, :-1]
                tf = masked_l1(nxt, y[:, 1:], m[:, 1:], dims)
                seq = x[:, :CONTEXT]
                roll = 0.0
                for s in range(k):
                    npose = model.step(seq[:, -RF:])
                    roll = roll + masked_l1(npose, y[:, CONTEXT + s], m[:, CONTEXT + s], dims)
                    seq = torch.cat([seq, as_features(npose, n_joints)[:, None]], 1)
                loss = tf + (roll / k if k > 0 else 0.0)
            opt.zero_grad()
            loss.backward()
            torch.nn.utils.clip_grad_norm_(model.parameters(), 1.0)
            opt.step()
            sched.step()
            losses.append(float(loss.detach()))
        if k == 0 and ep + 1 < len(schedule) and schedule[ep + 1] == 0:
            print(f"[{kind}] epoch {ep + 1}/{epochs} K=0 loss {np.mean(losses):.4f} "
                  f"({time.time() - t0:.0f} s)", flush=True)
            history.append({"epoch": ep + 1, "rollout_steps": 0, "loss": float(np.mean(losses)),
                            "seconds": round(time.time() - t0, 1)})
            continue
        v = validate(kind, model, val, n_joints, dims, args.horizons)
        score = float(np.mean(list(v.values())))
        history.append({"epoch": ep + 1, "rollout_steps": k, "loss": float(np.mean(losses)),
                        "val_pck": v, "seconds": round(time.time() - t0, 1)})
        print(f"[{kind}] epoch {ep + 1}/{epochs} K={k} loss {np.mean(losses):.4f} "
              f"val PCK {' '.join(f'{h}={p:.1f}' for h, p in v.items())} "
              f"({time.time() - t0:.0f} s)", flush=True)
        # select among epochs trained with the full curriculum when there are any
        if k == FUTURE or ep == epochs - 1:
            if score > best:
                best = score
                best_state = {kk: vv.clone() for kk, vv in model.state_dict().items()}
    model.load_state_dict(best_state)
    model.eval()
    best_ep = max((h for h in history if "val_pck" in h and (h["rollout_steps"] == FUTURE or h is history[-1])),
                  key=lambda h: np.mean(list(h["val_pck"].values())))
    return model, history, best_ep


# ----------------------------------------------------------------------------- export

def export(module, args_, path, input_names, output_names, dynamic_axes):
    module.eval()
    kwargs = dict(input_names=input_names, output_names=output_names,
                  dynamic_axes=dynamic_axes, opset_version=17, do_constant_folding=True)
    try:
        torch.onnx.export(module, args_, path, dynamo=False, **kwargs)
    except TypeError:
        torch.onnx.export(module, args_, path, **kwargs)


def sha256(path):
    h = hashlib.sha256()
    with open(path, "rb") as f:
        h.update(f.read())
    return h.hexdigest()


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--data", required=True)
    ap.add_argument("--out", required=True, help="models go to OUT/<dataset>/")
    ap.add_argument("--fixture-dir", help="write the ONNX parity fixture <dataset>_parity.json here")
    ap.add_argument("--epochs", type=int, default=8)
    ap.add_argument("--pose-epochs", type=int, default=None)
    ap.add_argument("--pretrain-epochs", type=int, default=6,
                    help="latent model: epochs of teacher forcing only before the curriculum")
    ap.add_argument("--pretrain-factor", type=int, default=4,
                    help="samples per teacher-forcing epoch = factor x samples per epoch")
    ap.add_argument("--samples-per-epoch", type=int, default=4096)
    ap.add_argument("--batch", type=int, default=64)
    ap.add_argument("--channels", type=int, default=64)
    ap.add_argument("--groups", type=int, default=8)
    ap.add_argument("--lr", type=float, default=2e-3)
    ap.add_argument("--latent-weight", type=float, default=0.1)
    ap.add_argument("--stride", type=int, default=2, help="frames between training windows")
    ap.add_argument("--val-stride", type=int, default=3)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--threads", type=int, default=1)
    ap.add_argument("--command", default=" ".join(sys.argv))
    args = ap.parse_args()
    if args.pose_epochs is None:
        args.pose_epochs = args.epochs
    args.horizons = [1, 5, 10, 20, 30]
    torch.set_num_threads(args.threads)
    np.random.seed(args.seed)
    torch.manual_seed(args.seed)

    kind, names, clips, action = load_dataset(args.data)
    hips, shoulders, flip = pairs(names)
    n_joints = len(names)
    dims = clips[0][0].shape[2]
    n_pose = n_joints * dims
    n_feat = n_pose + n_joints
    val_idx = [i for i in range(len(clips)) if i % VAL_EVERY == 0]
    train_idx = [i for i in range(len(clips)) if i % VAL_EVERY != 0]
    t0 = time.time()
    train = make_windows(clips, train_idx, hips, shoulders, args.stride)
    # validation windows must hold the whole 30-frame horizon of the rollout
    global FUTURE
    saved = FUTURE
    FUTURE = EVAL_HORIZON
    val = make_windows(clips, val_idx, hips, shoulders, args.val_stride)
    FUTURE = saved
    print(f"{kind}: {len(train_idx)} train clips -> {train[0].shape[0]} windows, "
          f"{len(val_idx)} validation clips -> {val[0].shape[0]} windows "
          f"({time.time() - t0:.0f} s)", flush=True)

    out_dir = os.path.join(args.out, kind)
    os.makedirs(out_dir, exist_ok=True)
    results = {}
    models = {}
    for k in ("latent", "pose"):
        m, hist, best = train_one(k, args, train, val, n_feat, n_pose, n_joints, dims, flip)
        models[k] = m
        results[k] = {"history": hist, "selected_epoch": best["epoch"], "val_pck": best["val_pck"]}

    files = {}
    lat_model = models["latent"]
    enc_path = os.path.join(out_dir, "encoder.onnx")
    export(EncoderExport(lat_model), (torch.zeros(1, CONTEXT, n_feat),), enc_path,
           ["frames"], ["latent", "pose"],
           {"frames": {0: "batch", 1: "time"}, "latent": {0: "batch", 1: "time"},
            "pose": {0: "batch", 1: "time"}})
    step_path = os.path.join(out_dir, "ar_step.onnx")
    export(ArStepExport(lat_model), (torch.zeros(1, RF, args.channels),), step_path,
           ["latents"], ["next_latent", "next_pose"],
           {"latents": {0: "batch"}, "next_latent": {0: "batch"}, "next_pose": {0: "batch"}})
    pose_path = os.path.join(out_dir, "pose_ar_step.onnx")
    export(PoseStepExport(models["pose"]), (torch.zeros(1, RF, n_feat),), pose_path,
           ["frames"], ["next_pose"], {"frames": {0: "batch"}, "next_pose": {0: "batch"}})
    for p in (enc_path, step_path, pose_path):
        files[os.path.basename(p)] = {"sha256": sha256(p), "bytes": os.path.getsize(p)}

    manifest = {
        "dataset": kind,
        "data": os.path.basename(args.data),
        "joints": names,
        "dims": dims,
        "features": n_feat,
        "pose_values": n_pose,
        "channels": args.channels,
        "groups": args.groups,
        "context_frames": CONTEXT,
        "receptive_field_frames": RF,
        "train_rollout_frames": FUTURE,
        "validation": f"clips with index % {VAL_EVERY} == 0 ({len(val_idx)} clips, windows every {args.val_stride} frames)",
        "train_clips": len(train_idx),
        "train_windows": int(train[0].shape[0]),
        "seed": args.seed,
        "epochs": args.epochs,
        "pose_epochs": args.pose_epochs,
        "pretrain_epochs": args.pretrain_epochs,
        "pretrain_factor": args.pretrain_factor,
        "samples_per_epoch": args.samples_per_epoch,
        "batch": args.batch,
        "lr": args.lr,
        "command": args.command,
        "torch": torch.__version__,
        "opset": 17,
        "normalisation": "per window from the context frames: anchor = root (mean of valid hips) of the latest "
                         "context frame that has one; scale = median torso length |mid-shoulders - root| over "
                         "the context (fallback: largest bounding-box side / 3); missing joints -> 0, mask 0",
        "models": {
            "latent": {"encoder": "encoder.onnx", "step": "ar_step.onnx",
                       "selected_epoch": results["latent"]["selected_epoch"],
                       "val_pck_no_dtw": results["latent"]["val_pck"]},
            "pose": {"step": "pose_ar_step.onnx",
                     "selected_epoch": results["pose"]["selected_epoch"],
                     "val_pck_no_dtw": results["pose"]["val_pck"]},
        },
        "files": files,
        "training_seconds": round(time.time() - t0, 1),
        "history": {k: v["history"] for k, v in results.items()},
    }
    with open(os.path.join(out_dir, "manifest.json"), "w") as f:
        json.dump(manifest, f, indent=2)

    if args.fixture_dir:
        # A fixed synthetic input (no data from the data sets): a swaying, arm-waving figure.
        g = torch.Generator().manual_seed(1234)
        t = torch.arange(CONTEXT, dtype=torch.float32)[:, None]
        base = torch.randn(n_joints * dims, generator=g) * 0.8
        phase = torch.rand(n_joints * dims, generator=g) * 6.28
        coords = base[None] + 0.3 * torch.sin(0.4 * t + phase[None])
        mask = torch.ones(CONTEXT, n_joints)
        mask[3, 2] = 0.0
        coords.view(CONTEXT, n_joints, dims)[3, 2] = 0.0
        x = torch.cat([coords, mask], 1)[None]
        with torch.no_grad():
            lat, pose = lat_model.encode(x), lat_model.readout(lat_model.encode(x))
            # raw read-out: what `ForecastModels::rollout_normalised` returns
            roll, _ = rollout_latent(lat_model, x, EVAL_HORIZON, n_pose, dims, anchor=False)
            proll = rollout_pose(models["pose"], x, EVAL_HORIZON, n_joints)
        fixture = {
            "description": "ONNX parity fixture: a fixed synthetic input (seeded) and the PyTorch outputs",
            "context_frames": CONTEXT, "features": n_feat, "pose_values": n_pose,
            "horizon": EVAL_HORIZON,
            "input": x[0].tolist(),
            "encoder_pose": pose[0].tolist(),
            "latent_rollout": roll[0].tolist(),
            "pose_rollout": proll[0].tolist(),
            "model_sha256": {k: v["sha256"] for k, v in files.items()},
        }
        os.makedirs(args.fixture_dir, exist_ok=True)
        with open(os.path.join(args.fixture_dir, f"{kind}_parity.json"), "w") as f:
            json.dump(fixture, f)
    print(json.dumps({k: manifest["models"][k] for k in manifest["models"]}, indent=1))


if __name__ == "__main__":
    main()
