#!/usr/bin/env python3
"""Trains the six refinement networks of mp-refine and exports them to ONNX.

Run through `cargo xtask train-refine`, which builds the dataset npz
(`mp_eval::refine::dataset`: canonical 60-frame clips, anchor flags, concept ids)
and calls this script with the training virtual environment's Python.

Writes into --out: anchor_recognition.onnx, anchor_refinement.onnx,
transition_generator.onnx, transition_refinement.onnx, generator.onnx,
evaluator.onnx, flaw_detector.onnx (trained on --flaw-dataset: flawed copies
of the clips of the training subjects and the mocap windows, its epoch
chosen on the selection subjects; --flaw-train-subjects and
--flaw-select-subjects pick a cross-validation fold), manifest.json and parity.npz (a fixed seeded input batch of 2
for every network with the PyTorch output; ONNX Runtime must agree within 1e-4).
The tensor contract is in models/refine/README.md.
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

T = 60            # frames per clip
J = 20            # joints
D = J * 3         # features per frame
K = 80            # global concepts (20 actions x 4)
N_ACTIONS = 20
TR_FRAMES = 16    # frames of a resampled transition
Z_TR = 16         # transition CVAE latent
Z_GEN = 32        # generator latent
D_MODEL = 64
OPSET = 17

NETS = ["anchor_recognition", "anchor_refinement", "transition_generator",
        "transition_refinement", "generator", "evaluator", "flaw_detector"]


# ----------------------------------------------------------------------------
# building blocks


def sinusoidal(n, d):
    pos = torch.arange(n, dtype=torch.float32)[:, None]
    i = torch.arange(0, d, 2, dtype=torch.float32)[None, :]
    ang = pos / torch.pow(10000.0, i / d)
    pe = torch.zeros(n, d)
    pe[:, 0::2] = torch.sin(ang)
    pe[:, 1::2] = torch.cos(ang)
    return pe


class Block(nn.Module):
    """Pre-norm transformer encoder block (explicit attention: exports to plain ONNX ops)."""

    def __init__(self, d=D_MODEL, heads=4, ffn=128, drop=0.1):
        super().__init__()
        self.h = heads
        self.dh = d // heads
        self.ln1 = nn.LayerNorm(d)
        self.qkv = nn.Linear(d, 3 * d)
        self.proj = nn.Linear(d, d)
        self.ln2 = nn.LayerNorm(d)
        self.ff = nn.Sequential(nn.Linear(d, ffn), nn.GELU(), nn.Linear(ffn, d))
        self.drop = nn.Dropout(drop)

    def forward(self, x):
        n = x.shape[1]
        q, k, v = self.qkv(self.ln1(x)).chunk(3, dim=-1)
        q = q.reshape(-1, n, self.h, self.dh).transpose(1, 2)
        k = k.reshape(-1, n, self.h, self.dh).transpose(1, 2)
        v = v.reshape(-1, n, self.h, self.dh).transpose(1, 2)
        att = torch.softmax(q @ k.transpose(-1, -2) / math.sqrt(self.dh), dim=-1)
        o = (att @ v).transpose(1, 2).reshape(-1, n, self.h * self.dh)
        x = x + self.drop(self.proj(o))
        return x + self.drop(self.ff(self.ln2(x)))


class Encoder(nn.Module):
    """Linear frame embedding + sinusoidal positions + transformer blocks."""

    def __init__(self, d_in, n, blocks=2, d=D_MODEL):
        super().__init__()
        self.emb = nn.Linear(d_in, d)
        self.register_buffer("pe", sinusoidal(n, d))
        self.blocks = nn.ModuleList([Block(d) for _ in range(blocks)])
        self.ln = nn.LayerNorm(d)

    def forward(self, x):
        h = self.emb(x) + self.pe
        for b in self.blocks:
            h = b(h)
        return self.ln(h)


def mlp(d_in, hidden, d_out, layers=2):
    mods, d = [], d_in
    for _ in range(layers):
        mods += [nn.Linear(d, hidden), nn.GELU()]
        d = hidden
    mods.append(nn.Linear(d, d_out))
    return nn.Sequential(*mods)


def linear_coeffs(anchor_a, anchor_b, delta):
    """Cubic coefficients = straight line from a to b plus a learned residual `delta [B,4,60]`."""
    base = torch.stack([anchor_a, anchor_b - anchor_a,
                        torch.zeros_like(anchor_a), torch.zeros_like(anchor_a)], dim=1)
    return base + delta


# ----------------------------------------------------------------------------
# the six networks


class AnchorRecognition(nn.Module):
    def __init__(self):
        super().__init__()
        self.enc = Encoder(D, T)
        self.head = nn.Sequential(nn.Linear(D_MODEL, D_MODEL), nn.GELU(), nn.Linear(D_MODEL, 1))

    def forward(self, motion):
        return self.head(self.enc(motion)).squeeze(-1)


class AnchorRefinement(nn.Module):
    """Masked-anchor encoder → concept classifier; MLP decoder of [anchor feature, concept
    embedding] → residual on the linear interpolation between the unmasked frames that
    bound the mask (the nearer one weighs more; the only one at the clip's ends)."""

    def __init__(self):
        super().__init__()
        self.enc = Encoder(D + 2, T)
        self.cls = mlp(D_MODEL, 128, K, layers=1)
        self.concept = nn.Embedding(K, 32)
        self.dec = mlp(D_MODEL + 32, 256, D, layers=2)
        self.register_buffer("idx", torch.arange(T, dtype=torch.float32)[None, :])

    def features(self, motion, mask, target):
        x = torch.cat([motion * (1.0 - mask[..., None]), mask[..., None], target[..., None]], dim=-1)
        h = self.enc(x)
        return (h * target[..., None]).sum(dim=1)

    def base(self, motion, mask, target):
        keep = 1.0 - mask
        zero = torch.zeros_like(mask[:, :1])
        # Unmasked frame right before / after a masked one.
        b_lo = keep * torch.cat([mask[:, 1:], zero], dim=1)
        b_hi = keep * torch.cat([zero, mask[:, :-1]], dim=1)
        has_lo = b_lo.sum(dim=1, keepdim=True).clamp(max=1.0)
        has_hi = b_hi.sum(dim=1, keepdim=True).clamp(max=1.0)
        pos_lo = (b_lo * self.idx).sum(dim=1, keepdim=True)
        pos_hi = (b_hi * self.idx).sum(dim=1, keepdim=True)
        pos_a = (target * self.idx).sum(dim=1, keepdim=True)
        t = (pos_a - pos_lo) / (pos_hi - pos_lo).clamp(min=1.0)
        w_hi = has_hi * (has_lo * t + (1.0 - has_lo))
        w_lo = has_lo * (has_hi * (1.0 - t) + (1.0 - has_hi))
        p_lo = (b_lo[..., None] * motion).sum(dim=1)
        p_hi = (b_hi[..., None] * motion).sum(dim=1)
        return w_lo * p_lo + w_hi * p_hi

    def decode(self, feat, emb, base):
        return base + self.dec(torch.cat([feat, emb], dim=-1))

    def forward(self, motion, mask, target):
        feat = self.features(motion, mask, target)
        logits = self.cls(feat)
        emb = self.concept(torch.argmax(logits, dim=-1))
        return logits, self.decode(feat, emb, self.base(motion, mask, target))


class TransitionGenerator(nn.Module):
    """CVAE decoder (exported) + encoder (training only)."""

    def __init__(self):
        super().__init__()
        self.dec = mlp(2 * D + 1 + Z_TR, 256, 4 * D, layers=2)
        self.enc = mlp(2 * D + 1 + TR_FRAMES * D, 256, 2 * Z_TR, layers=2)

    def encode(self, anchor_a, anchor_b, duration, transition):
        h = self.enc(torch.cat([anchor_a, anchor_b, duration, transition.flatten(1)], dim=-1))
        return h[:, :Z_TR], h[:, Z_TR:]

    def forward(self, anchor_a, anchor_b, duration, z):
        delta = self.dec(torch.cat([anchor_a, anchor_b, duration, z], dim=-1)).reshape(-1, 4, D)
        return linear_coeffs(anchor_a, anchor_b, 0.1 * delta)


class TransitionRefinement(nn.Module):
    """Concept encoder (anchors + duration → concept token) + bias encoder (the
    transition's frames, relative to the straight line between the anchors) + transformer."""

    def __init__(self):
        super().__init__()
        self.concept = mlp(2 * D + 1, 128, D_MODEL, layers=1)
        self.bias = nn.Linear(2 * D, D_MODEL)
        self.register_buffer("pe", sinusoidal(TR_FRAMES + 1, D_MODEL))
        s = torch.linspace(0.0, 1.0, TR_FRAMES)
        self.register_buffer("s", s[None, :, None])
        self.blocks = nn.ModuleList([Block() for _ in range(2)])
        self.ln = nn.LayerNorm(D_MODEL)
        self.head = mlp(2 * D_MODEL, 128, 4 * D, layers=1)

    def forward(self, transition, anchor_a, anchor_b, duration):
        line = anchor_a[:, None, :] + self.s * (anchor_b - anchor_a)[:, None, :]
        frames = torch.cat([transition - line, transition - anchor_a[:, None, :]], dim=-1)
        c = self.concept(torch.cat([anchor_a, anchor_b, duration], dim=-1))
        tok = torch.cat([c[:, None, :], self.bias(frames)], dim=1) + self.pe
        for b in self.blocks:
            tok = b(tok)
        tok = self.ln(tok)
        feat = torch.cat([tok[:, 0], tok[:, 1:].mean(dim=1)], dim=-1)
        delta = self.head(feat).reshape(-1, 4, D)
        return linear_coeffs(anchor_a, anchor_b, 0.1 * delta)


class Generator(nn.Module):
    """Action-conditioned CVAE: GRU decoder (exported) + MLP encoder (training only)."""

    def __init__(self, hidden=128):
        super().__init__()
        self.init = mlp(N_ACTIONS + Z_GEN, hidden, hidden, layers=1)
        self.inp = nn.Linear(N_ACTIONS + Z_GEN + 16, hidden)
        self.register_buffer("pe", sinusoidal(T, 16))
        self.gru = nn.GRU(hidden, hidden, batch_first=True)
        self.out = nn.Linear(hidden, D)
        self.enc = mlp(T * D + N_ACTIONS, 256, 2 * Z_GEN, layers=2)

    def encode(self, motion, action):
        h = self.enc(torch.cat([motion.flatten(1), action], dim=-1))
        return h[:, :Z_GEN], h[:, Z_GEN:]

    def forward(self, action, z):
        c = torch.cat([action, z], dim=-1)
        h0 = torch.tanh(self.init(c))[None]
        pe = self.pe[None].expand(c.shape[0], T, 16)
        x = self.inp(torch.cat([c[:, None, :].expand(c.shape[0], T, c.shape[1]), pe], dim=-1))
        y, _ = self.gru(x, h0)
        return self.out(y)


class Evaluator(nn.Module):
    def __init__(self, hidden=64):
        super().__init__()
        self.inp = nn.Linear(2 * D + 3, hidden)
        self.gru = nn.GRU(hidden, hidden, batch_first=True)
        self.drop_in = nn.Dropout(0.2)
        self.drop = nn.Dropout(0.3)
        self.cls = nn.Linear(hidden, N_ACTIONS)

    def forward(self, motion):
        # Pose relative to each frame's hip centre, the hip trajectory, and
        # frame-to-frame velocities (first frame: zero velocity).
        hip = motion[:, :, 18:21]
        rel = motion - hip.repeat(1, 1, J)
        vel = torch.cat([torch.zeros_like(motion[:, :1]), motion[:, 1:] - motion[:, :-1]], dim=1)
        x = torch.tanh(self.inp(torch.cat([rel, hip, 10.0 * vel], dim=-1)))
        y, _ = self.gru(self.drop_in(x))
        feat = y.mean(dim=1)
        return self.cls(self.drop(feat)), feat


class FlawDetector(nn.Module):
    """Per-frame, per-joint flaw logits. Frame tokens (pose relative to the hip
    centre, hip trajectory, velocity, acceleration) go through a transformer
    encoder; a head shared by the joints reads the frame token, a joint
    embedding and the joint's own local motion (position, velocities and
    accelerations of the frame and its neighbours)."""

    def __init__(self, d=D_MODEL, blocks=2, joint_emb=8):
        super().__init__()
        self.emb = nn.Linear(D + 3 + 2 * D, d)
        self.register_buffer("pe", sinusoidal(T, d))
        self.blocks = nn.ModuleList([Block(d) for _ in range(blocks)])
        self.ln = nn.LayerNorm(d)
        self.joint = nn.Parameter(0.1 * torch.randn(J, joint_emb))
        self.head = nn.Sequential(nn.Linear(d + joint_emb + 20, 64), nn.GELU(), nn.Linear(64, 1))

    def forward(self, motion):
        b = motion.shape[0]
        hip = motion[:, :, 18:21]
        rel = motion - hip.repeat(1, 1, J)
        z1 = torch.zeros_like(motion[:, :1])
        vel = 10.0 * torch.cat([z1, motion[:, 1:] - motion[:, :-1]], dim=1)
        acc = 10.0 * torch.cat([z1, motion[:, 2:] - 2.0 * motion[:, 1:-1] + motion[:, :-2], z1], dim=1)
        h = self.emb(torch.cat([rel, hip, vel, acc], dim=-1)) + self.pe
        for blk in self.blocks:
            h = blk(h)
        h = self.ln(h)
        # Joint-local features: [rel, vel(t), vel(t+1), acc(t-1), acc(t), acc(t+1), |acc(t)|, |vel(t)|] per joint.
        vel_n = torch.cat([vel[:, 1:], z1], dim=1)
        acc_p = torch.cat([z1, acc[:, :-1]], dim=1)
        acc_n = torch.cat([acc[:, 1:], z1], dim=1)
        loc = torch.stack([rel, vel, vel_n, acc_p, acc, acc_n], dim=-1)  # B,T,60,6
        loc = loc.reshape(b, T, J, 3, 6).transpose(3, 4).reshape(b, T, J, 18)
        an = acc.reshape(b, T, J, 3).norm(dim=-1, keepdim=True)
        vn = vel.reshape(b, T, J, 3).norm(dim=-1, keepdim=True)
        jl = torch.cat([loc, an, vn], dim=-1)  # B,T,J,20
        je = self.joint[None, None].expand(b, T, J, self.joint.shape[1])
        hj = h[:, :, None, :].expand(b, T, J, h.shape[-1])
        return self.head(torch.cat([hj, je, jl], dim=-1)).squeeze(-1)


# ----------------------------------------------------------------------------
# data helpers


def mpjpe(pred, gt, weight=None):
    """Mean per-joint position error; `pred`, `gt` [..., 60]; `weight` broadcast over [...]."""
    e = (pred - gt).reshape(*pred.shape[:-1], J, 3).norm(dim=-1).mean(dim=-1)
    if weight is None:
        return e.mean()
    return (e * weight).sum() / weight.sum().clamp(min=1.0)


def eval_coeffs(coeffs, s):
    """coeffs [B,4,D], s [B,L] → frames [B,L,D]."""
    pw = torch.stack([torch.ones_like(s), s, s * s, s * s * s], dim=-1)
    return pw @ coeffs


def rot_y(x, yaw):
    """Rotates features [B,...,60] about +y by yaw [B]."""
    c, s = torch.cos(yaw), torch.sin(yaw)
    p = x.reshape(*x.shape[:-1], J, 3)
    shape = [-1] + [1] * (p.dim() - 2)
    c, s = c.reshape(shape), s.reshape(shape)
    xr = c * p[..., 0] + s * p[..., 2]
    zr = -s * p[..., 0] + c * p[..., 2]
    return torch.stack([xr, p[..., 1], zr], dim=-1).reshape(x.shape)


def resample_np(x, n):
    """Linear resampling over the whole duration (frame 0 ↦ 0, last ↦ n−1), like mp_refine::motion::resample."""
    t = x.shape[0]
    if t == 1:
        return np.repeat(x, n, axis=0)
    u = np.arange(n) * (t - 1) / (n - 1)
    i0 = np.minimum(np.floor(u).astype(int), t - 1)
    i1 = np.minimum(i0 + 1, t - 1)
    w = (u - i0)[:, None]
    return (1 - w) * x[i0] + w * x[i1]


def time_warp(motion, rng, strength=0.15):
    """Random monotone time warp of clips [B,60,60] (numpy)."""
    out = np.empty_like(motion)
    for i in range(motion.shape[0]):
        i0, i1, w = warp_grid(rng, strength)
        out[i] = (1 - w) * motion[i, i0] + w * motion[i, i1]
    return out


def warp_grid(rng, strength):
    """One random monotone time warp of the T canonical frames: for each
    warped frame, the two source frames it interpolates and the weight of
    the second ([T, 1])."""
    g = np.cumsum(np.exp(rng.normal(0, strength, T - 1)))
    g = np.concatenate([[0.0], g / g[-1]]) * (T - 1)
    i0 = np.minimum(np.floor(g).astype(int), T - 1)
    i1 = np.minimum(i0 + 1, T - 1)
    return i0, i1, (g - i0)[:, None]


class Data:
    def __init__(self, path):
        z = np.load(path)
        self.motion = z["motion"].astype(np.float32)
        self.action = z["action"].astype(np.int64)
        self.subject = z["subject"].astype(np.int64)
        self.split = z["split"].astype(np.int64)
        self.anchor = z["anchor"].astype(np.float32)
        self.concept = z["concept"].astype(np.int64)
        self.train = np.nonzero(self.split == 0)[0]
        self.val = np.nonzero(self.split == 1)[0]

    def anchor_items(self, idx):
        """(clip, anchor index k, frame a, lo, hi, concept) for every anchor of clips idx."""
        items = []
        for i in idx:
            a = np.nonzero(self.anchor[i] > 0.5)[0]
            for k in range(len(a)):
                lo = a[k - 1] if k > 0 else -1
                hi = a[k + 1] if k + 1 < len(a) else T
                items.append((i, a[k], lo, hi, self.concept[i, a[k]]))
        return np.array(items, dtype=np.int64)

    def transitions(self, idx):
        """Consecutive anchor pairs: anchor_a, anchor_b, duration, frames padded to 31, mask, 16-frame resample."""
        aa, bb, dur, fr, mk, rs, src = [], [], [], [], [], [], []
        for i in idx:
            a = np.nonzero(self.anchor[i] > 0.5)[0]
            for p, q in zip(a[:-1], a[1:]):
                seg = self.motion[i, p:q + 1]
                pad = np.zeros((T + 1, D), np.float32)
                pad[:len(seg)] = seg
                m = np.zeros(T + 1, np.float32)
                m[:len(seg)] = 1
                aa.append(seg[0])
                bb.append(seg[-1])
                dur.append([(q - p) / T])
                fr.append(pad)
                mk.append(m)
                rs.append(resample_np(seg, TR_FRAMES))
                src.append(i)
        L = int(max(m.sum() for m in mk))
        return {
            "a": torch.tensor(np.array(aa)), "b": torch.tensor(np.array(bb)),
            "dur": torch.tensor(np.array(dur, np.float32)),
            "frames": torch.tensor(np.array(fr)[:, :L]), "mask": torch.tensor(np.array(mk)[:, :L]),
            "rs": torch.tensor(np.array(rs, np.float32)), "clip": np.array(src),
        }


def frame_s(tr):
    """Normalised time of every padded transition frame: s = f / (b − a)."""
    L = tr["frames"].shape[1]
    f = torch.arange(L, dtype=torch.float32)[None, :]
    steps = tr["dur"] * T
    return f / steps


def batches(n, bs, rng):
    perm = rng.permutation(n)
    for s in range(0, n, bs):
        yield perm[s:s + bs]


class Trainer:
    def __init__(self, args):
        self.args = args
        self.log = {}

    def opt(self, model):
        return torch.optim.Adam([p for p in model.parameters() if p.requires_grad], lr=self.args.lr)


def n_params(m, exclude=()):
    return sum(p.numel() for n, p in m.named_parameters() if not any(n.startswith(e) for e in exclude))


# ----------------------------------------------------------------------------
# training loops


def train_anchor_recognition(data, args, rng, log):
    model = AnchorRecognition()
    opt = torch.optim.Adam(model.parameters(), lr=args.lr)
    x = torch.tensor(data.motion)
    y = torch.tensor(data.anchor)
    tr, va = data.train, data.val
    pos = y[tr].mean().item()
    pw = torch.tensor((1 - pos) / max(pos, 1e-6))
    epochs = max(1, int(args.epochs * 1.5))
    for ep in range(epochs):
        model.train()
        for b in batches(len(tr), args.batch, rng):
            i = tr[b]
            xb = x[i]
            yaw = torch.tensor(rng.uniform(-0.3, 0.3, len(i)), dtype=torch.float32)
            xb = rot_y(xb, yaw)
            loss = F.binary_cross_entropy_with_logits(model(xb), y[i], pos_weight=pw)
            opt.zero_grad()
            loss.backward()
            opt.step()
    model.eval()
    with torch.no_grad():
        lt = F.binary_cross_entropy_with_logits(model(x[tr]), y[tr], pos_weight=pw).item()
        lo = model(x[va])
        lv = F.binary_cross_entropy_with_logits(lo, y[va], pos_weight=pw).item()
        pred = (lo > 0).float()
        tp = (pred * y[va]).sum().item()
        prec = tp / max(pred.sum().item(), 1)
        rec = tp / max(y[va].sum().item(), 1)
        # Within ±1 frame.
        near = lambda v: F.max_pool1d(v[:, None], 3, stride=1, padding=1)[:, 0]
        prec1 = (pred * near(y[va])).sum().item() / max(pred.sum().item(), 1)
        rec1 = (y[va] * near(pred)).sum().item() / max(y[va].sum().item(), 1)
    log.update(train_loss=lt, val_loss=lv, val_precision=prec, val_recall=rec,
               val_precision_1frame=prec1, val_recall_1frame=rec1,
               pos_weight=float(pw), epochs=epochs)
    return model


def refinement_batch(data, items, x, rng, yaw=True):
    i, a, lo, hi, c = [torch.tensor(items[:, k]) for k in range(5)]
    f = torch.arange(T)[None, :]
    mask = ((f > lo[:, None]) & (f < hi[:, None])).float()
    target = (f == a[:, None]).float()
    xb = x[i]
    if yaw:
        xb = rot_y(xb, torch.tensor(rng.uniform(-0.3, 0.3, len(i)), dtype=torch.float32))
    gt = xb[torch.arange(len(i)), a]
    return xb * (1 - mask[..., None]), mask, target, c, gt


def train_anchor_refinement(data, args, rng, log):
    model = AnchorRefinement()
    opt = torch.optim.Adam(model.parameters(), lr=args.lr)
    x = torch.tensor(data.motion)
    tr_items = data.anchor_items(data.train)
    va_items = data.anchor_items(data.val)
    epochs = max(1, int(args.epochs * 0.25))
    for ep in range(epochs):
        model.train()
        for b in batches(len(tr_items), args.batch, rng):
            m, mask, target, c, gt = refinement_batch(data, tr_items[b], x, rng)
            feat = model.features(m, mask, target)
            logits = model.cls(feat)
            # Ground-truth concept as the decoder's input (paper), sometimes the predicted one.
            use_pred = torch.tensor(rng.random(len(c)) < 0.3)
            cid = torch.where(use_pred, logits.argmax(-1).detach(), c)
            anchor = model.decode(feat, model.concept(cid), model.base(m, mask, target))
            loss = F.cross_entropy(logits, c) + mpjpe(anchor, gt)
            opt.zero_grad()
            loss.backward()
            opt.step()
    model.eval()

    def evaluate(items):
        r = np.random.default_rng(0)
        with torch.no_grad():
            m, mask, target, c, gt = refinement_batch(data, items, x, r, yaw=False)
            logits, anchor = model(m, mask, target)
            ce = F.cross_entropy(logits, c).item()
            mp = mpjpe(anchor, gt).item()
            acc = (logits.argmax(-1) == c).float().mean().item()
            base = mpjpe(model.base(m, mask, target), gt).item()
        return ce, mp, acc, base

    tce, tmp, tacc, _ = evaluate(tr_items)
    vce, vmp, vacc, vbase = evaluate(va_items)
    log.update(train_loss=tce + tmp, val_loss=vce + vmp, train_ce=tce, train_mpjpe_m=tmp,
               val_ce=vce, val_mpjpe_m=vmp, val_concept_accuracy=vacc,
               val_interpolation_mpjpe_m=vbase, epochs=epochs)
    return model


def train_transition_generator(data, args, rng, log):
    model = TransitionGenerator()
    opt = torch.optim.Adam(model.parameters(), lr=args.lr)
    tr = data.transitions(data.train)
    va = data.transitions(data.val)

    def loss_of(d, idx, sample=True):
        a, b, dur = d["a"][idx], d["b"][idx], d["dur"][idx]
        mu, logvar = model.encode(a, b, dur, d["rs"][idx])
        z = mu + torch.randn_like(mu) * torch.exp(0.5 * logvar) if sample else mu
        coeffs = model(a, b, dur, z)
        s = frame_s({"frames": d["frames"][idx], "dur": dur})
        frames = eval_coeffs(coeffs, s)
        lt = mpjpe(frames, d["frames"][idx], d["mask"][idx])
        ends = eval_coeffs(coeffs, torch.tensor([[0.0, 1.0]]).expand(len(a), 2))
        la = mpjpe(ends, torch.stack([a, b], dim=1))
        kl = (-0.5 * (1 + logvar - mu * mu - logvar.exp()).sum(-1)).mean()
        return lt + 0.5 * la + 1e-4 * kl, lt, la, kl

    n = len(tr["a"])
    epochs = max(1, int(args.epochs * 1))
    for ep in range(epochs):
        model.train()
        for b in batches(n, args.batch, rng):
            loss = loss_of(tr, torch.tensor(b))[0]
            opt.zero_grad()
            loss.backward()
            opt.step()
    model.eval()
    with torch.no_grad():
        torch.manual_seed(args.seed)
        t = [v.item() for v in loss_of(tr, torch.arange(n))]
        v = [v.item() for v in loss_of(va, torch.arange(len(va["a"])))]
        # Prior sample (z = 0): what the refinement uses.
        a, b2, dur = va["a"], va["b"], va["dur"]
        coeffs = model(a, b2, dur, torch.zeros(len(a), Z_TR))
        s = frame_s(va)
        v0 = mpjpe(eval_coeffs(coeffs, s), va["frames"], va["mask"]).item()
        lin = mpjpe(eval_coeffs(linear_coeffs(a, b2, torch.zeros(len(a), 4, D)), s), va["frames"], va["mask"]).item()
    log.update(train_loss=t[0], val_loss=v[0], train_mpjpe_t_m=t[1], val_mpjpe_t_m=v[1],
               val_mpjpe_a_m=v[2], val_kl=v[3], val_mpjpe_t_zero_z_m=v0,
               val_mpjpe_t_linear_m=lin, transitions_train=n, epochs=epochs)
    return model


def corrupt(rs, pool, rng):
    """Flaws on resampled transitions rs [B,16,60] (numpy): jitter, frozen frames,
    offset (jump) and a wrong middle pose from `pool` [P,60]; anchors (frames 0 and 15) stay."""
    x = rs.copy()
    B = x.shape[0]
    for i in range(B):
        kinds = rng.choice(5, size=rng.integers(1, 3), replace=False)
        for k in kinds:
            L = int(rng.integers(2, 9))
            s0 = int(rng.integers(1, TR_FRAMES - 1 - L + 1)) if TR_FRAMES - 1 - L >= 1 else 1
            sl = slice(s0, min(s0 + L, TR_FRAMES - 1))
            if k == 0:  # jitter
                x[i, sl] += rng.normal(0, rng.uniform(0.01, 0.05), x[i, sl].shape)
            elif k == 1:  # frozen
                x[i, sl] = x[i, s0 - 1]
            elif k == 2:  # offset / jump
                off = rng.normal(0, 1, 3)
                off = off / np.linalg.norm(off) * rng.uniform(0.03, 0.15)
                x[i, sl] += np.tile(off, J)
            elif k == 3:  # wrong middle pose, blended in
                p = pool[rng.integers(len(pool))].reshape(J, 3)
                mid = int(rng.integers(3, TR_FRAMES - 3))
                cur = x[i, mid].reshape(J, 3)
                p = p - p[6] + cur[6]
                for d in range(-2, 3):
                    w = 1.0 - abs(d) / 3.0
                    x[i, mid + d] = (1 - w) * x[i, mid + d] + w * p.reshape(-1)
            # k == 4: left clean
    return x.astype(np.float32)


def train_transition_refinement(data, args, rng, log):
    model = TransitionRefinement()
    opt = torch.optim.Adam(model.parameters(), lr=args.lr)
    tr = data.transitions(data.train)
    va = data.transitions(data.val)
    pool = data.motion[data.train].reshape(-1, D)

    def loss_of(d, idx, flawed):
        a, b, dur = d["a"][idx], d["b"][idx], d["dur"][idx]
        coeffs = model(flawed, a, b, dur)
        s = frame_s({"frames": d["frames"][idx], "dur": dur})
        ls = mpjpe(eval_coeffs(coeffs, s), d["frames"][idx], d["mask"][idx])
        ends = eval_coeffs(coeffs, torch.tensor([[0.0, 1.0]]).expand(len(a), 2))
        lc = mpjpe(ends, torch.stack([a, b], dim=1))
        return ls + lc, ls, lc

    n = len(tr["a"])
    epochs = max(1, int(args.epochs * 0.5))
    rs_np = tr["rs"].numpy()
    for ep in range(epochs):
        model.train()
        for b in batches(n, args.batch, rng):
            flawed = torch.tensor(corrupt(rs_np[b], pool, rng))
            loss = loss_of(tr, torch.tensor(b), flawed)[0]
            opt.zero_grad()
            loss.backward()
            opt.step()
    model.eval()
    r = np.random.default_rng(1)
    with torch.no_grad():
        t = [v.item() for v in loss_of(tr, torch.arange(n), torch.tensor(corrupt(rs_np, pool, r)))]
        fl = corrupt(va["rs"].numpy(), pool, r)
        v = [v.item() for v in loss_of(va, torch.arange(len(va["a"])), torch.tensor(fl))]
        # Reference: error of the flawed input itself (on its 16 frames, vs the clean 16 frames).
        vin = mpjpe(torch.tensor(fl), va["rs"]).item()
        s16 = torch.linspace(0, 1, TR_FRAMES)[None].expand(len(va["a"]), TR_FRAMES)
        vout = mpjpe(eval_coeffs(model(torch.tensor(fl), va["a"], va["b"], va["dur"]), s16), va["rs"]).item()
    log.update(train_loss=t[0], val_loss=v[0], train_l_s_m=t[1], train_l_c_m=t[2],
               val_l_s_m=v[1], val_l_c_m=v[2], val_flawed_input_mpjpe16_m=vin,
               val_refined_mpjpe16_m=vout, transitions_train=n, epochs=epochs)
    return model


class FlawData:
    def __init__(self, path):
        z = np.load(path)
        self.motion = z["motion"].astype(np.float32)
        self.mask = z["mask"].astype(np.float32)
        self.split = z["split"].astype(np.int64)
        self.flaws = z["flaws"]
        self.subject = z["subject"].astype(np.int64)
        self.train = np.nonzero(self.split == 0)[0]
        self.sel = np.nonzero(self.split == 1)[0]

    def use_subjects(self, train, select):
        """Cross-validation folds: rows of the `train` subjects and the mocap
        windows (subject -1) train, rows of the `select` subjects choose the
        epoch; rows of any other subject are not read."""
        if set(train) & set(select):
            raise SystemExit(f"train.py: subjects {sorted(set(train) & set(select))} are both training and selection subjects")
        self.train = np.nonzero(np.isin(self.subject, list(train) + [-1]))[0]
        self.sel = np.nonzero(np.isin(self.subject, list(select)))[0]
        for what, rows, subj in (("training", self.train, train), ("selection", self.sel, select)):
            missing = sorted(set(subj) - {int(s) for s in self.subject[rows]})
            if missing:
                raise SystemExit(f"train.py: the flaw dataset holds no clips of {what} subjects {missing}")

    def subjects(self, rows):
        """MSR subjects of the rows (mocap windows, subject -1, left out)."""
        return sorted({int(s) for s in self.subject[rows] if s >= 0})


def prf(prob, y, thr):
    pred = prob > thr
    tp = float((pred & (y > 0.5)).sum())
    prec = tp / max(float(pred.sum()), 1.0)
    rec = tp / max(float((y > 0.5).sum()), 1.0)
    return prec, rec


# Left/right joint pairs of the MSR 20-joint skeleton (shoulders, hips,
# elbows, wrists, hands, knees, ankles, feet).
MIRROR_PAIRS = [(0, 1), (4, 5), (7, 8), (9, 10), (11, 12), (13, 14), (15, 16), (17, 18)]
MIRROR_PERM = list(range(J))
for _a, _b in MIRROR_PAIRS:
    MIRROR_PERM[_a], MIRROR_PERM[_b] = _b, _a


def mirror_np(motion, mask):
    """Left-right mirror of canonical clips [B,60,60] (x -> -x, the hip axis of
    the canonical frame) with their masks [B,60,20]: left and right joints swap,
    so the mirrored body keeps the canonical convention (left hip at +x)."""
    p = motion.reshape(*motion.shape[:-1], J, 3)[..., MIRROR_PERM, :].copy()
    p[..., 0] *= -1.0
    return p.reshape(motion.shape), mask[..., MIRROR_PERM]


def warp_pair_np(motion, mask, rng, strength=0.15):
    """The same random monotone time warp of clips [B,60,60] and their masks
    [B,60,20]; a warped frame is flawed when a frame it interpolates (with
    non-zero weight) is, as in mp_refine::motion::canonical_mask."""
    out, mout = np.empty_like(motion), np.empty_like(mask)
    for i in range(motion.shape[0]):
        i0, i1, w = warp_grid(rng, strength)
        out[i] = (1 - w) * motion[i, i0] + w * motion[i, i1]
        mout[i] = np.maximum(mask[i, i0] * (w < 1 - 1e-9), mask[i, i1] * (w > 1e-9))
    return out, mout


def augment_flaw_batch(xb, yb, rng, full):
    """Augmentation of the flaw detector's batches: random yaw (±0.3 rad) and
    scale; with `full` also body scale 0.85–1.15, left-right mirroring (half
    the rows) and a random time warp, i.e. a change of speed within the clip
    (half the rows)."""
    n = xb.shape[0]
    if full:
        xb, yb = xb.numpy().copy(), yb.numpy().copy()
        m = rng.random(n) < 0.5
        if m.any():
            xb[m], yb[m] = mirror_np(xb[m], yb[m])
        w = rng.random(n) < 0.5
        if w.any():
            xb[w], yb[w] = warp_pair_np(xb[w], yb[w], rng)
        xb, yb = torch.tensor(xb), torch.tensor(yb)
        lo, hi = 0.85, 1.15
    else:
        lo, hi = 0.9, 1.1
    xb = rot_y(xb, torch.tensor(rng.uniform(-0.3, 0.3, n), dtype=torch.float32))
    xb = xb * torch.tensor(rng.uniform(lo, hi, (n, 1, 1)), dtype=torch.float32)
    return xb, yb


def train_flaw_detector(data, args, rng, log):
    fd = data.flaw
    model = FlawDetector()
    opt = torch.optim.Adam(model.parameters(), lr=args.lr * 2, weight_decay=1e-5)
    x = torch.tensor(fd.motion)
    y = torch.tensor(fd.mask)
    tr, se = fd.train, fd.sel
    pos = y[tr].mean().item()
    pw = torch.tensor(args.flaw_pos_weight)
    epochs = max(1, int(args.epochs * args.flaw_epochs_factor))
    best, best_state, hist = None, None, []
    bs = 64
    for ep in range(epochs):
        model.train()
        for b in batches(len(tr), bs, rng):
            i = tr[b]
            xb, yb = augment_flaw_batch(x[i], y[i], rng, args.flaw_augment == "full")
            loss = F.binary_cross_entropy_with_logits(model(xb), yb, pos_weight=pw)
            opt.zero_grad()
            loss.backward()
            opt.step()
        if (ep + 1) % max(1, epochs // 10) == 0 or ep + 1 == epochs:
            model.eval()
            with torch.no_grad():
                lv = F.binary_cross_entropy_with_logits(model(x[se]), y[se], pos_weight=pw).item()
            hist.append((ep + 1, round(lv, 4)))
            print(f"train.py: flaw_detector epoch {ep + 1}: selection loss {lv:.4f}", flush=True)
            if best is None or lv < best:
                best = lv
                best_state = {k: v.clone() for k, v in model.state_dict().items()}
                best_ep = ep + 1
    model.load_state_dict(best_state)
    model.eval()
    with torch.no_grad():
        lt = F.binary_cross_entropy_with_logits(model(x[tr]), y[tr], pos_weight=pw).item()
        ps = torch.sigmoid(model(x[se])).numpy()
    ys = fd.mask[se]
    metrics = {}
    for thr in (0.3, 0.5, 0.7, 0.9):
        p_, r_ = prf(ps, ys, thr)
        metrics[f"select_precision_at_{thr}"] = p_
        metrics[f"select_recall_at_{thr}"] = r_
    # Frame level (a frame is flawed when any joint is).
    pf, rf = prf(ps.max(-1), ys.max(-1), 0.5)
    clean = np.array([f == "clean" for f in fd.flaws[se]])
    clean_flag = float((ps[clean] > 0.5).mean()) if clean.any() else float("nan")
    log.update(train_loss=lt, select_loss=best, selected_epoch=best_ep, select_loss_history=hist,
               select_frame_precision_at_0_5=pf, select_frame_recall_at_0_5=rf,
               select_clean_cells_flagged_at_0_5=clean_flag, pos_weight=float(pw),
               train_clips=int(len(tr)), select_clips=int(len(se)), epochs=epochs,
               augment=args.flaw_augment, **metrics)
    return model


def train_evaluator(data, args, rng, log):
    model = Evaluator()
    opt = torch.optim.Adam(model.parameters(), lr=args.lr * 2, weight_decay=1e-4)
    tr = data.train[data.action[data.train] >= 0]
    va = data.val
    x = torch.tensor(data.motion)
    y = torch.tensor(data.action)
    epochs = max(1, int(args.epochs * 6))
    for ep in range(epochs):
        model.train()
        for b in batches(len(tr), args.batch, rng):
            i = tr[b]
            xb = time_warp(data.motion[i], rng)
            xb = torch.tensor(xb) * torch.tensor(rng.uniform(0.9, 1.1, (len(i), 1, 1)), dtype=torch.float32)
            xb = rot_y(xb, torch.tensor(rng.uniform(-0.5, 0.5, len(i)), dtype=torch.float32))
            xb = xb + 0.01 * torch.randn_like(xb)
            loss = F.cross_entropy(model(xb)[0], y[i])
            opt.zero_grad()
            loss.backward()
            opt.step()
    model.eval()
    with torch.no_grad():
        lt = F.cross_entropy(model(x[tr])[0], y[tr]).item()
        at = (model(x[tr])[0].argmax(-1) == y[tr]).float().mean().item()
        lo = model(x[va])[0]
        lv = F.cross_entropy(lo, y[va]).item()
        av = (lo.argmax(-1) == y[va]).float().mean().item()
    log.update(train_loss=lt, val_loss=lv, train_accuracy=at, val_accuracy=av,
               val_clips=int(len(va)), epochs=epochs)
    return model


def train_generator(data, args, rng, log, evaluator):
    model = Generator()
    opt = torch.optim.Adam(model.parameters(), lr=args.lr * 2)
    tr = data.train[data.action[data.train] >= 0]
    va = data.val
    x = torch.tensor(data.motion)
    y = torch.tensor(data.action)
    kl_w = args.generator_kl

    def loss_of(i, aug=None):
        xb = x[i] if aug is None else aug
        oh = F.one_hot(y[i], N_ACTIONS).float()
        mu, logvar = model.encode(xb, oh)
        z = mu + torch.randn_like(mu) * torch.exp(0.5 * logvar)
        rec = mpjpe(model(oh, z), xb)
        kl = (-0.5 * (1 + logvar - mu * mu - logvar.exp()).sum(-1)).mean()
        return rec + kl_w * kl, rec, kl

    epochs = max(1, int(args.epochs * 6))
    for ep in range(epochs):
        model.train()
        for b in batches(len(tr), args.batch, rng):
            i = tr[b]
            xb = rot_y(x[i], torch.tensor(rng.uniform(-0.2, 0.2, len(i)), dtype=torch.float32))
            loss = loss_of(i, xb)[0]
            opt.zero_grad()
            loss.backward()
            opt.step()
    model.eval()
    torch.manual_seed(args.seed + 7)
    with torch.no_grad():
        t = [v.item() for v in loss_of(tr)]
        v = [v.item() for v in loss_of(va)]
        # Samples from the prior, 10 per action, classified by the evaluator.
        act = torch.arange(N_ACTIONS).repeat_interleave(10)
        gen = model(F.one_hot(act, N_ACTIONS).float(), torch.randn(len(act), Z_GEN))
        acc = (evaluator(gen)[0].argmax(-1) == act).float().mean().item()
        jerk_gen = (gen[:, 2:] - 2 * gen[:, 1:-1] + gen[:, :-2]).abs().mean().item()
        jerk_real = (x[tr][:, 2:] - 2 * x[tr][:, 1:-1] + x[tr][:, :-2]).abs().mean().item()
    log.update(train_loss=t[0], val_loss=v[0], train_mpjpe_m=t[1], val_mpjpe_m=v[1],
               train_kl=t[2], kl_weight=kl_w, prior_sample_evaluator_accuracy=acc,
               prior_sample_accel_mean_m=jerk_gen, real_accel_mean_m=jerk_real, epochs=epochs)
    return model


# ----------------------------------------------------------------------------
# export


SPECS = {
    "anchor_recognition": (["motion"], [[T, D]], ["anchor_logit"]),
    "anchor_refinement": (["motion", "mask", "target"], [[T, D], [T], [T]],
                          ["concept_logits", "anchor"]),
    "transition_generator": (["anchor_a", "anchor_b", "duration", "z"], [[D], [D], [1], [Z_TR]],
                             ["coeffs"]),
    "transition_refinement": (["transition", "anchor_a", "anchor_b", "duration"],
                              [[TR_FRAMES, D], [D], [D], [1]], ["coeffs"]),
    "generator": (["action", "z"], [[N_ACTIONS], [Z_GEN]], ["motion"]),
    "evaluator": (["motion"], [[T, D]], ["logits", "features"]),
    "flaw_detector": (["motion"], [[T, D]], ["flaw_logit"]),
}


def parity_inputs(name, data, seed):
    """A fixed input batch of 2 for each network (seeded, from real validation data where it fits)."""
    g = np.random.default_rng(seed + NETS.index(name))
    va = data.val
    clips = data.motion[va[:2]]
    if name in ("anchor_recognition", "evaluator"):
        return [clips]
    if name == "flaw_detector":
        # Two flawed clips of the selection subject.
        fd = data.flaw
        rows = [i for i in fd.sel if fd.flaws[i] != "clean"][:2]
        return [fd.motion[rows]]
    if name == "anchor_refinement":
        items = data.anchor_items(va[:2])
        pick = [items[items[:, 0] == va[0]][2], items[items[:, 0] == va[1]][3]]
        m, mask, target, _, _ = refinement_batch(data, np.array(pick), torch.tensor(data.motion), g, yaw=False)
        return [m.numpy(), mask.numpy(), target.numpy()]
    tr = data.transitions(va[:2])
    a, b, dur = tr["a"][:2].numpy(), tr["b"][:2].numpy(), tr["dur"][:2].numpy()
    if name == "transition_generator":
        return [a, b, dur, g.standard_normal((2, Z_TR)).astype(np.float32)]
    if name == "transition_refinement":
        fl = corrupt(tr["rs"][:2].numpy(), data.motion[data.train].reshape(-1, D), g)
        return [fl, a, b, dur]
    if name == "generator":
        oh = np.zeros((2, N_ACTIONS), np.float32)
        oh[0, 3] = 1
        oh[1, 17] = 1
        return [oh, g.standard_normal((2, Z_GEN)).astype(np.float32)]
    raise ValueError(name)


def export(name, model, inputs, out_dir):
    ins, shapes, outs = SPECS[name]
    model.eval()
    path = os.path.join(out_dir, name + ".onnx")
    args_ = tuple(torch.tensor(v, dtype=torch.float32) for v in inputs)
    dyn = {n: {0: "B"} for n in ins + outs}
    kwargs = dict(input_names=ins, output_names=outs, dynamic_axes=dyn, opset_version=OPSET,
                  do_constant_folding=True)
    try:
        torch.onnx.export(model, args_, path, dynamo=False, **kwargs)
    except TypeError:
        torch.onnx.export(model, args_, path, **kwargs)
    with torch.no_grad():
        res = model(*args_)
    if not isinstance(res, tuple):
        res = (res,)
    return path, [r.numpy() for r in res]


def check_onnx(path, ins, inputs, expected, outs, rng):
    import onnxruntime as ort
    sess = ort.InferenceSession(path, providers=["CPUExecutionProvider"])
    got = sess.run(outs, {n: v.astype(np.float32) for n, v in zip(ins, inputs)})
    worst = 0.0
    for g, e in zip(got, expected):
        assert g.shape == e.shape, (path, g.shape, e.shape)
        worst = max(worst, float(np.abs(g - e).max()))
    # A different batch size must run too (dynamic batch axis).
    big = [np.repeat(v, 3, axis=0)[:5] for v in inputs]
    got5 = sess.run(outs, {n: v.astype(np.float32) for n, v in zip(ins, big)})
    for g in got5:
        assert g.shape[0] == 5, (path, g.shape)
    return worst


def sha256(path):
    h = hashlib.sha256()
    with open(path, "rb") as f:
        h.update(f.read())
    return h.hexdigest()


# ----------------------------------------------------------------------------


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--dataset", required=True)
    ap.add_argument("--out", required=True)
    ap.add_argument("--epochs", type=float, default=100,
                    help="base passes over the data; per network: anchor recognition ×1.5, anchor refinement ×0.25, "
                         "transition generator ×1, transition refinement ×0.5, evaluator and generator ×6")
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--lr", type=float, default=5e-4)
    ap.add_argument("--batch", type=int, default=128)
    ap.add_argument("--generator-kl", type=float, default=2e-3)
    ap.add_argument("--threads", type=int, default=2)
    ap.add_argument("--only", default="", help="comma-separated networks to train (others kept from an existing manifest)")
    ap.add_argument("--command", default="")
    ap.add_argument("--flaw-dataset", default="", help="flaw detector training set (flaw_dataset.npz)")
    ap.add_argument("--flaw-pos-weight", type=float, default=1.0,
                    help="positive weight of the flaw detector's BCE (1: calibrated probabilities)")
    ap.add_argument("--flaw-epochs-factor", type=float, default=0.15,
                    help="flaw detector epochs = --epochs × this")
    ap.add_argument("--flaw-train-subjects", default="",
                    help="comma-separated MSR subjects whose rows train the flaw detector (with the mocap windows); "
                         "default: the dataset's own split")
    ap.add_argument("--flaw-select-subjects", default="",
                    help="comma-separated MSR subjects whose rows choose the flaw detector's epoch")
    ap.add_argument("--flaw-augment", choices=["full", "yaw-scale"], default="full",
                    help="flaw detector augmentation: full = yaw, scale 0.85-1.15, mirrored bodies, time warp; "
                         "yaw-scale = yaw and scale 0.9-1.1 only")
    args = ap.parse_args()

    torch.set_num_threads(args.threads)
    torch.manual_seed(args.seed)
    rng = np.random.default_rng(args.seed)
    os.makedirs(args.out, exist_ok=True)
    data = Data(args.dataset)
    data.flaw = FlawData(args.flaw_dataset) if args.flaw_dataset else None
    if args.flaw_train_subjects or args.flaw_select_subjects:
        if data.flaw is None:
            raise SystemExit("train.py: --flaw-train-subjects needs --flaw-dataset")
        ints = lambda v: [int(x) for x in v.split(",") if x]
        data.flaw.use_subjects(ints(args.flaw_train_subjects), ints(args.flaw_select_subjects))
    print(f"train.py: {len(data.motion)} clips, {len(data.train)} train, {len(data.val)} val", flush=True)

    only = [s for s in args.only.split(",") if s]
    man_path = os.path.join(args.out, "manifest.json")
    old, old_training = {}, None
    if only and os.path.exists(man_path):
        with open(man_path) as f:
            old_man = json.load(f)
        old = old_man.get("networks", {})
        old_training = old_man.get("training")

    t_all = time.time()
    models, logs = {}, {}
    trainers = {
        "anchor_recognition": train_anchor_recognition,
        "anchor_refinement": train_anchor_refinement,
        "transition_generator": train_transition_generator,
        "transition_refinement": train_transition_refinement,
        "evaluator": train_evaluator,
        "flaw_detector": train_flaw_detector,
    }
    order = ["evaluator", "anchor_recognition", "anchor_refinement", "transition_generator",
             "transition_refinement", "generator", "flaw_detector"]
    for name in order:
        if only and name not in only:
            continue
        if name == "flaw_detector" and data.flaw is None:
            print("train.py: no --flaw-dataset: flaw_detector skipped", file=sys.stderr)
            continue
        torch.manual_seed(args.seed + NETS.index(name))
        r = np.random.default_rng(args.seed + 100 + NETS.index(name))
        log = {}
        t0 = time.time()
        if name == "generator":
            ev = models.get("evaluator")
            if ev is None:
                ev = Evaluator()
                ev_path = os.path.join(os.path.dirname(args.dataset), "evaluator.pt")
                ev.load_state_dict(torch.load(ev_path))
                ev.eval()
            models[name] = train_generator(data, args, r, log, ev)
        else:
            models[name] = trainers[name](data, args, r, log)
        log["train_seconds"] = round(time.time() - t0, 1)
        logs[name] = log
        if name == "evaluator":
            torch.save(models[name].state_dict(), os.path.join(os.path.dirname(args.dataset), "evaluator.pt"))
        print(f"train.py: {name}: " + ", ".join(f"{k}={v:.4g}" if isinstance(v, float) else f"{k}={v}"
                                                for k, v in log.items()), flush=True)

    # Export, parity, verification.
    parity_path = os.path.join(args.out, "parity.npz")
    parity = dict(np.load(parity_path)) if (only and os.path.exists(parity_path)) else {}
    nets = dict(old)
    exclude = {"transition_generator": ("enc.",), "generator": ("enc.",)}
    for name in NETS:
        if name not in models:
            continue
        ins, shapes, outs = SPECS[name]
        inputs = [np.asarray(v, np.float32) for v in parity_inputs(name, data, args.seed)]
        path, expected = export(name, models[name], inputs, args.out)
        worst = check_onnx(path, ins, inputs, expected, outs, rng)
        if worst > 1e-4:
            print(f"train.py: {name}: ONNX differs from PyTorch by {worst}", file=sys.stderr)
            sys.exit(1)
        for n, v in zip(ins, inputs):
            parity[f"{name}.{n}"] = v
        for n, v in zip(outs, expected):
            parity[f"{name}.{n}"] = v
        nets[name] = {
            "file": name + ".onnx",
            "sha256": sha256(path),
            "bytes": os.path.getsize(path),
            "inputs": {n: ["B"] + s for n, s in zip(ins, shapes)},
            "outputs": {n: ["B"] + list(e.shape[1:]) for n, e in zip(outs, expected)},
            "params": n_params(models[name], exclude.get(name, ())),
            "params_training": n_params(models[name]),
            "onnx_max_abs_diff": worst,
            "metrics": logs[name],
        }
        if name == "flaw_detector":
            nets[name]["training"] = {
                "command": args.command,
                "dataset": os.path.basename(args.flaw_dataset),
                "train_subjects": data.flaw.subjects(data.flaw.train),
                "train_mocap_windows": bool((data.flaw.subject[data.flaw.train] < 0).any()),
                "select_subjects": data.flaw.subjects(data.flaw.sel),
                "rows_train": int(len(data.flaw.train)),
                "rows_select": int(len(data.flaw.sel)),
                "epochs": logs[name]["epochs"],
                "selected_epoch": logs[name]["selected_epoch"],
                "seed": args.seed,
                "optimizer": "Adam",
                "lr": args.lr * 2,
                "batch": 64,
                "augment": args.flaw_augment,
                "threads": args.threads,
                "torch": torch.__version__,
            }
        print(f"train.py: {name}.onnx {os.path.getsize(path) / 1e6:.2f} MB, "
              f"{nets[name]['params']} params, ONNX vs torch max |Δ| {worst:.2e}", flush=True)
    np.savez(parity_path, **parity)
    manifest = {
        "format": "mp-refine networks",
        "opset": OPSET,
        "frames": T,
        "features": D,
        "joints": J,
        "concepts": K,
        "transition_frames": TR_FRAMES,
        "transition_latent": Z_TR,
        "generator_latent": Z_GEN,
        "d_model": D_MODEL,
        "training": old_training if old_training is not None else {
            "command": args.command,
            "dataset": os.path.basename(args.dataset),
            "clips": int(len(data.motion)),
            "train_clips": int(len(data.train)),
            "val_clips": int(len(data.val)),
            "train_subjects": sorted({int(s) for s in data.subject[data.train] if s >= 0}),
            "val_subjects": sorted({int(s) for s in data.subject[data.val] if s >= 0}),
            "epochs": args.epochs,
            "seed": args.seed,
            "optimizer": "Adam",
            "lr": args.lr,
            "batch": args.batch,
            "generator_kl_weight": args.generator_kl,
            "torch": torch.__version__,
            "wall_seconds": round(time.time() - t_all, 1),
        },
        "networks": {n: nets[n] for n in NETS if n in nets},
    }
    with open(man_path, "w") as f:
        json.dump(manifest, f, indent=2)
    print(f"train.py: wrote {man_path} and {parity_path} in {time.time() - t_all:.0f} s total", flush=True)


if __name__ == "__main__":
    main()
