#!/usr/bin/env python3
"""Stand-in for OMNet (Xu et al., ICCV 2021; the PyTorch port hxwork/OMNet_Pytorch) in PyTorch,
for the parity test networks/families/omnet/omnet_test.cpp. Written here from a reading of the
authors' model/module.py and model/net.py: the same module tree and state-dict keys as their OMNet
(encoder.I, fusion.I, decoder.I, regression.I of Conv1d/Linear-BN-ReLU Sequentials), and an
independent forward pass of their inference: four iterations, masks from the third on, the
source moved by each iteration's pose (quaternion rotation of the points, as theirs) and the
poses composed with a quaternion product.

Where it departs from the authors' code, on purpose and as regbench does
(networks/families/omnet/net.hpp):
clouds of different sizes are max-pooled each over its own points before the regressor (theirs
concatenates per-point features of both clouds along the channels, which fails unless N == M;
for N == M this script follows theirs literally). `width_divisor` divides every hidden width.

Weights and clouds come from the formula of scripts/ogmm_reference.py (formula_fill,
formula_cloud, formula_motion), which tests/networks/formula_fixture.hpp repeats in C++; since the
formula is keyed by the tensor's name, equal outputs also show that regbench's parameter names
are the authors' keys. BatchNorm in eval mode (the authors' test mode).

Not a dependency of the product; run by hand with Debian's python3-torch:
  omnet_standin.py expected
      prints the transforms, masks and loss terms of the test's cases in float64, as JSON,
      and the overlap biases that make the masks mixed (see balance).
  omnet_standin.py authors AUTHORS_DIR
      runs the authors' OMNet from AUTHORS_DIR (a checkout of hxwork/OMNet_Pytorch; CUDA calls
      mapped to the CPU, transforms3d's euler2quat of zero angles given as (1, 0, 0, 0)) with
      the same formula weights (float32: their code fixes the dtype) on the equal-size cases
      and prints how far their transform is from this script's.
  omnet_standin.py time AUTHORS_DIR [POINTS]
      CPU time of the authors' OMNet forward (eval, no gradient, one torch thread) on a pair of
      POINTS (717) uniform random points, five runs after a warm-up.
  omnet_standin.py save FILE DIVISOR
      the authors' checkpoint layout at width / DIVISOR, formula weights: torch.save (zip) of
      {"state_dict": {"module." + key: tensor}, "optimizer": ..., "scheduler": ...,
      "step", "epoch", "best_val_score", "best_test_score"}, as their common/manager.py saves
      it (the optimizer's and scheduler's state of one Adam step).
"""
import json
import os
import sys
import time
import types

import torch
import torch.nn as nn
import torch.nn.functional as F

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "..", "scripts"))
from ogmm_reference import formula_cloud, formula_fill, formula_motion  # noqa: E402

ITERATIONS = 4
MASK_DELAY = 2

# --------------------------------------------------------------------------- module layout


def block(layer, i, o):
    norm = nn.BatchNorm1d(o)
    return nn.Sequential(layer(i, o, 1) if layer is nn.Conv1d else layer(i, o), norm, nn.ReLU())


class Encoder(nn.Module):
    def __init__(self, d):
        super().__init__()
        w = [3, 64 // d, 64 // d, 64 // d, 128 // d, 1024 // d]
        for n in range(5):
            setattr(self, "conv_block%d" % (n + 1), block(nn.Conv1d, w[n], w[n + 1]))


class Fusion(nn.Module):
    def __init__(self, d):
        super().__init__()
        w = [(64 + 2048) // d, 1024 // d, 1024 // d, 512 // d]
        for n in range(3):
            setattr(self, "conv_block%d" % (n + 1), block(nn.Conv1d, w[n], w[n + 1]))


class Decoder(nn.Module):
    def __init__(self, d):
        super().__init__()
        w = [512 // d, 512 // d, 256 // d, 256 // d]
        for n in range(3):
            setattr(self, "conv_block%d" % (n + 1), block(nn.Conv1d, w[n], w[n + 1]))
        self.conv_block4 = nn.Sequential(nn.Conv1d(256 // d, 2, 1))


class Regression(nn.Module):
    def __init__(self, d):
        super().__init__()
        w = [3072 // d, 2048 // d, 1024 // d, 512 // d, 256 // d]
        for n in range(4):
            setattr(self, "fc_block%d" % (n + 1), block(nn.Linear, w[n], w[n + 1]))
        self.final_fc = nn.Sequential(nn.Linear(256 // d, 7))


class OmnetLayout(nn.Module):
    def __init__(self, d=1):
        super().__init__()
        self.encoder = nn.ModuleList([Encoder(d) for _ in range(ITERATIONS)])
        self.fusion = nn.ModuleList([Fusion(d) for _ in range(ITERATIONS)])
        self.decoder = nn.ModuleList([Decoder(d) for _ in range(ITERATIONS)])
        self.regression = nn.ModuleList([Regression(d) for _ in range(ITERATIONS)])


# ------------------------------------------------------------------------------- forward


def run_blocks(module, names, x):
    outs = []
    for n in names:
        x = getattr(module, n)(x)
        outs.append(x)
    return outs


def quat_mul(b, a):
    """Hamilton product b * a of (w, x, y, z) quaternions [B, 4]: rotate by a, then by b."""
    bw, bv = b[:, :1], b[:, 1:]
    aw, av = a[:, :1], a[:, 1:]
    w = bw * aw - (bv * av).sum(1, keepdim=True)
    v = bw * av + aw * bv + torch.cross(bv, av, dim=1)
    return torch.cat([w, v], 1)


def quat_rotate(q, p):
    """Points p [B, N, 3] rotated by unit quaternions q [B, 4]: p + 2 (w u x p + u x (u x p))."""
    w = q[:, None, :1]
    u = q[:, None, 1:].expand_as(p)
    uv = torch.cross(u, p, dim=2)
    return p + 2 * (w * uv + torch.cross(u, uv, dim=2))


def quat_matrix(q):
    w, x, y, z = q.unbind(1)
    return torch.stack([
        torch.stack([w * w + x * x - y * y - z * z, 2 * (x * y - w * z), 2 * (x * z + w * y)], 1),
        torch.stack([2 * (x * y + w * z), w * w + y * y - x * x - z * z, 2 * (y * z - w * x)], 1),
        torch.stack([2 * (x * z - w * y), 2 * (y * z + w * x), w * w + z * z - x * x - y * y], 1)], 1)


def forward(net, src, tgt):
    """-> T [B, 4, 4], the masks each iteration used, logits and composed poses."""
    B, N, _ = src.shape
    M = tgt.shape[1]
    pose = torch.zeros(B, 7, dtype=src.dtype)
    pose[:, 0] = 1
    src_mask = torch.ones(B, N, dtype=src.dtype)
    tgt_mask = torch.ones(B, M, dtype=src.dtype)
    moved = src
    record = []
    for i in range(ITERATIONS):
        if i < MASK_DELAY:
            src_mask = torch.ones(B, N, dtype=src.dtype)
            tgt_mask = torch.ones(B, M, dtype=src.dtype)
        enc, fus, dec, reg = net.encoder[i], net.fusion[i], net.decoder[i], net.regression[i]
        names5 = ["conv_block%d" % n for n in range(1, 6)]
        s = run_blocks(enc, names5, moved.transpose(1, 2))
        t = run_blocks(enc, names5, tgt.transpose(1, 2))
        sm, tm = src_mask[:, None, :], tgt_mask[:, None, :]
        s_glob = (s[4] * sm).max(2, keepdim=True)[0]
        t_glob = (t[4] * tm).max(2, keepdim=True)[0]
        s_cat = torch.cat([s[1] * sm, s_glob.expand(-1, -1, N), t_glob.expand(-1, -1, N)], 1)
        t_cat = torch.cat([t[1] * tm, t_glob.expand(-1, -1, M), s_glob.expand(-1, -1, M)], 1)
        names3 = ["conv_block%d" % n for n in range(1, 4)]
        s_fused = run_blocks(fus, names3, s_cat)[-1] * sm
        t_fused = run_blocks(fus, names3, t_cat)[-1] * tm
        s_dec = run_blocks(dec, names3, s_fused)
        t_dec = run_blocks(dec, names3, t_fused)
        s_logits, t_logits = dec.conv_block4(s_dec[-1]), dec.conv_block4(t_dec[-1])
        s_feat = torch.cat(s_dec, 1) * sm
        t_feat = torch.cat(t_dec, 1) * tm
        if N == M:  # the authors' literal order: concatenate, then max over points
            pooled = torch.cat([s_fused, s_feat, t_fused, t_feat], 1).max(2)[0]
        else:
            pooled = torch.cat([s_fused.max(2)[0], s_feat.max(2)[0], t_fused.max(2)[0],
                                t_feat.max(2)[0]], 1)
        h = pooled
        for n in ["fc_block1", "fc_block2", "fc_block3", "fc_block4", "final_fc"]:
            h = getattr(reg, n)(h)
        step = torch.cat([F.normalize(h[:, :4], dim=1), h[:, 4:]], 1)
        moved = quat_rotate(step[:, :4], moved) + step[:, None, 4:]
        pose = torch.cat([quat_mul(step[:, :4], pose[:, :4]),
                          quat_rotate(step[:, :4], pose[:, None, 4:])[:, 0] + step[:, 4:]], 1)
        record.append(dict(src_mask=src_mask, tgt_mask=tgt_mask, src_logits=s_logits,
                           tgt_logits=t_logits, pose=pose))
        src_mask = s_logits.argmax(1).to(src.dtype)
        tgt_mask = t_logits.argmax(1).to(src.dtype)
    T = torch.eye(4, dtype=src.dtype).repeat(B, 1, 1)
    T[:, :3, :3] = quat_matrix(pose[:, :4])
    T[:, :3, 3] = pose[:, 4:]
    return T, record


def loss_terms(record, src, tgt, T_gt, overlap_dist=0.1, alpha1=1.0, alpha2=4.0):
    """The authors' compute_loss ("omnet"): per iteration the class-weighted cross-entropy of
    both clouds' overlap logits (labels as their generate_overlap_mask: masked-out points moved
    to 50 / 100), the L1 of the quaternion (times alpha1), the MSE of the translation (alpha2)."""
    R, t = T_gt[:, :3, :3], T_gt[:, :3, 3]
    # Quaternion of R with w >= 0 (rotations here are below 180 degrees: trace > -1).
    w = torch.sqrt(1 + R[:, 0, 0] + R[:, 1, 1] + R[:, 2, 2]) / 2
    q_gt = torch.stack([w, (R[:, 2, 1] - R[:, 1, 2]) / (4 * w), (R[:, 0, 2] - R[:, 2, 0]) / (4 * w),
                        (R[:, 1, 0] - R[:, 0, 1]) / (4 * w)], 1)
    weight = torch.tensor([0.7, 0.3], dtype=src.dtype)
    out = {}
    for i, r in enumerate(record):
        s = src.clone()
        g = tgt.clone()
        s[r["src_mask"] == 0] = 50.0
        g[r["tgt_mask"] == 0] = 100.0
        s = s @ R.transpose(1, 2) + t[:, None, :]
        d = torch.sqrt(((s[:, :, None, :] - g[:, None, :, :]) ** 2).sum(-1))
        s_gt = (d.min(2)[0] < overlap_dist).long()
        g_gt = (d.min(1)[0] < overlap_dist).long()
        out["overlap_%d" % i] = (F.cross_entropy(r["src_logits"], s_gt, weight=weight) +
                                 F.cross_entropy(r["tgt_logits"], g_gt, weight=weight)) / 2
        out["quat_%d" % i] = F.l1_loss(r["pose"][:, :4], q_gt) * alpha1
        out["trans_%d" % i] = F.mse_loss(r["pose"][:, 4:], t) * alpha2
    out["total"] = sum(out.values())
    return out


# ------------------------------------------------------------------------------- cases


def case_pair(batch, n, m):
    """Source formula_cloud(batch, n, 0); n == m: the target is the source moved by
    formula_motion and reversed in order; else formula_cloud(batch, m, 1) moved."""
    motion = formula_motion(batch).double()
    R, t = motion[:, :3, :3], motion[:, :3, 3][:, None, :]
    src = formula_cloud(batch, n, 0.0).double()
    if n == m:
        tgt = (src @ R.transpose(1, 2) + t).flip(1)
    else:
        tgt = formula_cloud(batch, m, 1.0).double() @ R.transpose(1, 2) + t
    return src, tgt, motion


CASES = [("full_width", 1, 1, 40, 40), ("divisor8_same", 8, 2, 60, 60),
         ("divisor8_different", 8, 1, 60, 47)]


def make_net(divisor, dtype, overlap_bias=None):
    """Formula weights; `overlap_bias` {I: b} then adds b to the overlapping class's bias of
    decoder.I.conv_block4 (so that the masks are neither all 0 nor all 1: see balance)."""
    torch.set_default_dtype(dtype)
    try:
        net = OmnetLayout(divisor)
    finally:
        torch.set_default_dtype(torch.float32)
    formula_fill(net)
    with torch.no_grad():
        for i, b in (overlap_bias or {}).items():
            net.decoder[i].conv_block4[0].bias[1] += b
    return net.eval()


def balance(divisor, src, tgt):
    """{I: b} for the iterations whose logits make a later iteration's mask: b = minus the
    midpoint of the middle two values over the source's points of logit(overlap) -
    logit(not), so about half of the source's points are masked out (formula weights alone
    give all-0 or all-1 masks) and none is near a tie."""
    bias = {}
    with torch.no_grad():
        for i in range(MASK_DELAY - 1, ITERATIONS - 1):
            _, record = forward(make_net(divisor, torch.float64, bias), src, tgt)
            logits = record[i]["src_logits"]
            d = (logits[:, 1] - logits[:, 0]).reshape(-1).sort()[0]
            k = d.numel() // 2  # midway between the middle two: no point near a tie
            bias[i] = -float(d[k - 1] + d[k]) / 2
    return bias


def expected():
    out = {}
    with torch.no_grad():
        for name, d, b, n, m in CASES:
            src, tgt, motion = case_pair(b, n, m)
            bias = balance(d, src, tgt)
            T, record = forward(make_net(d, torch.float64, bias), src, tgt)
            terms = loss_terms(record, src, tgt, motion)
            out[name] = dict(overlap_bias=bias, T=[float(v) for v in T.reshape(-1)],
                             mask_fraction=[float(r["src_mask"].mean()) for r in record] +
                             [float(r["tgt_mask"].mean()) for r in record],
                             loss={k: float(v) for k, v in terms.items()})
    print(json.dumps(out, indent=1))


def authors_module(authors_dir):
    """The authors' OMNet class on the CPU (their .cuda() calls return the tensor itself)."""
    torch.Tensor.cuda = lambda self, *a, **k: self
    t3d = types.ModuleType("transforms3d")
    t3d.euler = types.ModuleType("transforms3d.euler")
    t3d.euler.euler2quat = lambda *a, **k: __import__("numpy").array([1.0, 0.0, 0.0, 0.0])
    t3d.quaternions = types.ModuleType("transforms3d.quaternions")  # imported, not called
    sys.modules["transforms3d"] = t3d
    sys.modules["transforms3d.euler"] = t3d.euler
    sys.modules["transforms3d.quaternions"] = t3d.quaternions
    sys.path.insert(0, authors_dir)
    from model.net import OMNet  # noqa: E402
    return OMNet(types.SimpleNamespace(titer=ITERATIONS, overlap_dist=0.1))


def authors(authors_dir):
    theirs = authors_module(authors_dir)  # float32: their initial pose is .float()
    with torch.no_grad():
        for name, d, b, n, m in CASES:
            if d != 1 or n != m:
                continue
            src, tgt, motion = case_pair(b, n, m)
            bias = balance(d, src, tgt)
            formula_fill(theirs)
            for i, v in bias.items():
                theirs.decoder[i].conv_block4[0].bias[1] += v
            theirs.eval()
            ours, _ = forward(make_net(1, torch.float64, bias), src, tgt)
            ep = theirs({"points_src": src.float(), "points_ref": tgt.float(),
                         "transform_gt": motion[:, :3, :].float(), "pose_gt": torch.zeros(b, 7)})
            T = ep["transform_pair"][1]
            print(name, "max |T_authors - T_standin| =",
                  float((T.double() - ours[:, :3, :]).abs().max()), "(theirs in float32)")


def timing(authors_dir, points):
    torch.set_num_threads(1)
    net = authors_module(authors_dir).eval()
    src, tgt = torch.rand(1, points, 3), torch.rand(1, points, 3)
    data = {"points_src": src, "points_ref": tgt, "transform_gt": torch.eye(4)[None, :3, :],
            "pose_gt": torch.zeros(1, 7)}
    with torch.no_grad():
        net(data)
        times = []
        for _ in range(5):
            t0 = time.process_time()
            net(data)
            times.append(time.process_time() - t0)
    print(json.dumps({"points": points, "cpu_seconds": times,
                      "parameters": sum(p.numel() for p in net.parameters())}))


def save(path, divisor):
    """The authors' Manager.check_best_save_last_checkpoints layout, with the optimizer and
    scheduler state of one real Adam step under their ExponentialLR (so the file holds what
    theirs holds: tensors, ints, floats, bools, None, tuples)."""
    net = make_net(divisor, torch.float32)
    optimizer = torch.optim.Adam(net.parameters(), lr=1e-4)
    scheduler = torch.optim.lr_scheduler.ExponentialLR(optimizer, gamma=1)
    net.train()
    src, tgt, _ = case_pair(2, 30, 30)
    T, _ = forward(net, src.float(), tgt.float())
    T.sum().backward()
    optimizer.zero_grad(set_to_none=False)  # a step that leaves the weights as they are
    optimizer.step()
    scheduler.step()
    state = {"module." + k: v for k, v in make_net(divisor, torch.float32).state_dict().items()}
    torch.save({"state_dict": state, "optimizer": optimizer.state_dict(),
                "scheduler": scheduler.state_dict(), "step": 7, "epoch": 1,
                "best_val_score": float("inf"), "best_test_score": 0.5}, path)


if __name__ == "__main__":
    cmd = sys.argv[1] if len(sys.argv) > 1 else ""
    if cmd == "expected":
        expected()
    elif cmd == "authors":
        authors(sys.argv[2])
    elif cmd == "time":
        timing(sys.argv[2], int(sys.argv[3]) if len(sys.argv) > 3 else 717)
    elif cmd == "save":
        save(sys.argv[2], int(sys.argv[3]))
    else:
        sys.exit(__doc__)
