#!/usr/bin/env python3
"""Stand-in for RGM (Fu et al., CVPR 2021; authors' code fukexue/RGM) in PyTorch, for the parity
test networks/families/rgm/rgm_test.cpp. Written here from the paper and a reading of the
authors' models/Net.py, dgcnn.py, transformer.py, gconv.py, affinity_layer.py and eval.py (their
repository has no licence: nothing of it is copied): the same module tree and state-dict keys
as their Net with the ModelNet40 transformer configs (features xyz + gxyz, k 20, two graph
layers, 4 heads, Sinkhorn with slack, 20 iterations), and an independent forward and test-time
pipeline: per direction two rounds of match, scipy's linear_sum_assignment on the rows and
columns whose mass exceeds 0.5, weighted SVD and move; both directions, the pairs both find,
a final weighted SVD.

Where it departs from the authors' code, as regbench does (networks/families/rgm/net.hpp): the
correspondence gather takes the matched pairs only (theirs pairs unmatched rows with unmatched
columns, which fails unless N == M; the unmatched ones have weight 0 in the SVD either way); a round
with fewer than 3 pairs moves nothing. `divisor` divides every hidden width.

Weights: a seeded generator, rounded to float32 (the authors' files hold float32) and run in
float64; BatchNorm in eval mode with non-trivial running statistics; the instance norms'
scale 4 so the soft correspondences are peaked enough that rows and columns pass 0.5.

Not a dependency of the product; Debian's python3-torch and python3-scipy:
  rgm_standin.py write DIR DIVISOR
      DIR/rgm.pth: the state dict as the authors' save_model writes it (torch.save of
      model.state_dict(), zip format) and DIR/expected.json: the test's pairs and, per pair,
      the first match's soft correspondence, the loss against the ground-truth labels, the
      final pairs and transform.
"""
import json
import math
import os
import sys

import numpy as np
import torch
import torch.nn as nn
import torch.nn.functional as F
from scipy.optimize import linear_sum_assignment

K = 20
HEADS = 4
SINKHORN = 20
ROUNDS = 2
THRESHOLD = 0.5
LABEL_DIST = 0.05

# --------------------------------------------------------------------------- module layout


class Attention(nn.Module):
    def __init__(self, d):
        super().__init__()
        self.linears = nn.ModuleList([nn.Linear(d, d) for _ in range(4)])

    def forward(self, x, mem):
        b, p, d = x.shape
        dk = d // HEADS

        def split(lin, t):
            return lin(t).view(b, t.shape[1], HEADS, dk).permute(0, 2, 1, 3)

        q, k, v = split(self.linears[0], x), split(self.linears[1], mem), split(self.linears[2], mem)
        w = torch.softmax(q @ k.transpose(-1, -2) / math.sqrt(dk), dim=-1)
        return self.linears[3]((w @ v).permute(0, 2, 1, 3).reshape(b, p, d))


class Norm(nn.Module):
    def __init__(self, d):
        super().__init__()
        self.a_2 = nn.Parameter(torch.ones(d))
        self.b_2 = nn.Parameter(torch.zeros(d))

    def forward(self, x):
        return self.a_2 * (x - x.mean(-1, keepdim=True)) / (x.std(-1, keepdim=True) + 1e-6) + self.b_2


class Sub(nn.Module):
    def __init__(self, d):
        super().__init__()
        self.norm = Norm(d)


class FeedForward(nn.Module):
    def __init__(self, d, ff):
        super().__init__()
        self.w_1 = nn.Linear(d, ff)
        self.w_2 = nn.Linear(ff, d)

    def forward(self, x):
        return self.w_2(torch.relu(self.w_1(x)))


class Layer(nn.Module):
    def __init__(self, d, ff, decoder):
        super().__init__()
        self.self_attn = Attention(d)
        if decoder:
            self.src_attn = Attention(d)
        self.feed_forward = FeedForward(d, ff)
        self.sublayer = nn.ModuleList([Sub(d) for _ in range(3 if decoder else 2)])


class Stack(nn.Module):
    def __init__(self, d, ff, decoder):
        super().__init__()
        self.layers = nn.ModuleList([Layer(d, ff, decoder)])
        self.norm = Norm(d)


class Model(nn.Module):
    def __init__(self, d, ff):
        super().__init__()
        self.encoder = Stack(d, ff, False)
        self.decoder = Stack(d, ff, True)

    def encode(self, x):
        l = self.encoder.layers[0]
        n = l.sublayer[0].norm(x)
        x = x + l.self_attn(n, n)
        x = x + l.feed_forward(l.sublayer[1].norm(x))
        return self.encoder.norm(x)

    def decode(self, y, mem):
        l = self.decoder.layers[0]
        n = l.sublayer[0].norm(y)
        y = y + l.self_attn(n, n)
        y = y + l.src_attn(l.sublayer[1].norm(y), mem)
        y = y + l.feed_forward(l.sublayer[2].norm(y))
        return self.decoder.norm(y)


class Transformer(nn.Module):
    def __init__(self, d, ff):
        super().__init__()
        self.model = Model(d, ff)

    def forward(self, src, tgt):
        t = self.model.decode(tgt, self.model.encode(src)).transpose(1, 2)
        s = self.model.decode(src, self.model.encode(tgt)).transpose(1, 2)
        return s, t


class Features(nn.Module):
    def __init__(self, d):
        super().__init__()
        w = [6, 64 // d, 64 // d, 128 // d, 256 // d]
        for i in range(4):
            setattr(self, "conv%d" % (i + 1), nn.Conv2d(w[i], w[i + 1], 1, bias=False))
        self.conv5 = nn.Conv2d(sum(w[1:]), 512 // d, 1, bias=False)
        for i, c in enumerate(w[1:] + [512 // d]):
            setattr(self, "bn%d" % (i + 1), nn.BatchNorm2d(c))

    def forward(self, pts):  # [B, P, 3] -> [B, P, node + edge]
        b, p, _ = pts.shape
        k = min(K, p)
        d2 = torch.cdist(pts, pts) ** 2
        idx = d2.topk(k, dim=-1, largest=False)[1]  # [B, P, k]
        nb = torch.gather(pts.unsqueeze(1).expand(b, p, p, 3), 2, idx.unsqueeze(-1).expand(b, p, k, 3))
        ctr = pts.unsqueeze(2).expand(b, p, k, 3)
        x = torch.cat([nb, ctr], -1).permute(0, 3, 1, 2)  # [B, 6, P, k]: neighbour, centre
        pooled = []
        for i in range(1, 5):
            x = F.relu(getattr(self, "bn%d" % i)(getattr(self, "conv%d" % i)(x)))
            pooled.append(x.max(-1, keepdim=True)[0])
        node = torch.cat(pooled, 1)  # [B, C, P, 1]
        edge = F.relu(self.bn5(self.conv5(node)))
        return torch.cat([node, edge], 1).squeeze(-1).transpose(1, 2)


class Gconv(nn.Module):
    def __init__(self, i, o):
        super().__init__()
        self.a_fc = nn.Linear(i, o)
        self.u_fc = nn.Linear(i, o)


class GnnLayer(nn.Module):
    def __init__(self, i, o):
        super().__init__()
        self.gconv = Gconv(i, o)

    def forward(self, adj, x):
        adj = adj / adj.sum(-2, keepdim=True)
        return adj @ torch.relu(self.gconv.a_fc(x)) + torch.relu(self.gconv.u_fc(x))


class Affinity(nn.Module):
    def __init__(self, d):
        super().__init__()
        self.A = nn.Parameter(torch.eye(d))

    def forward(self, x, y):
        return x @ ((self.A + self.A.t()) / 2) @ y.transpose(1, 2)


def sinkhorn_slack(s, iters):
    n, m = s.shape[1], s.shape[2]
    la = F.pad(s, (0, 1, 0, 1))
    for _ in range(iters):
        la = torch.cat([la[:, :n] - torch.logsumexp(la[:, :n], 2, keepdim=True), la[:, n:]], 1)
        la = torch.cat([la[:, :, :m] - torch.logsumexp(la[:, :, :m], 1, keepdim=True), la[:, :, m:]], 2)
    return la[:, :n, :m]


class Net(nn.Module):
    def __init__(self, d):
        super().__init__()
        self.pointfeaturer = Features(d)
        emb, gnn, ff = (64 + 64 + 128 + 256 + 512) // d, 512 // d, 1024 // d
        for i in range(2):
            setattr(self, "gnn_layer_%d" % i, GnnLayer(emb if i == 0 else gnn, gnn))
            setattr(self, "affinity_%d" % i, Affinity(gnn))
            setattr(self, "gmattend%d" % i, Transformer(emb if i == 0 else gnn, ff))
            setattr(self, "InstNorm_layer_%d" % i, nn.InstanceNorm2d(1, affine=True))
        self.cross_graph_0 = nn.Linear(2 * gnn, gnn)

    def match(self, src, tgt):
        es, et = self.pointfeaturer(src), self.pointfeaturer(tgt)
        for i in range(2):
            a, b = getattr(self, "gmattend%d" % i)(es, et)
            dk = a.shape[1]
            adj_s = torch.softmax(a.transpose(1, 2) @ a / math.sqrt(dk), -1)
            adj_t = torch.softmax(b.transpose(1, 2) @ b / math.sqrt(dk), -1)
            g = getattr(self, "gnn_layer_%d" % i)
            es, et = g(adj_s, es), g(adj_t, et)
            s = getattr(self, "affinity_%d" % i)(es, et)
            s = getattr(self, "InstNorm_layer_%d" % i)(s[:, None]).squeeze(1)
            s = torch.exp(sinkhorn_slack(s, SINKHORN))
            if i == 0:
                es, et = (self.cross_graph_0(torch.cat([es, s @ et], -1)),
                          self.cross_graph_0(torch.cat([et, s.transpose(1, 2) @ es], -1)))
        return s


# --------------------------------------------------------------------------- test-time pipeline


def assign(s):  # s [N, M] float64 -> 0/1 [N, M]
    rows = np.where(s.sum(1) > THRESHOLD)[0]
    cols = np.where(s.sum(0) > THRESHOLD)[0]
    perm = np.zeros_like(s)
    if len(rows) and len(cols):
        r, c = linear_sum_assignment(-s[np.ix_(rows, cols)])
        perm[rows[r], cols[c]] = 1.0
    return perm


def rigid(p, q, w):  # the authors' SVDslover on one pair, float64 numpy
    wn = w[:, None] / (w.sum() + 1e-5)
    cp, cq = (p * wn).sum(0), (q * wn).sum(0)
    cov = (p - cp).T @ ((q - cq) * wn)
    u, _, vt = np.linalg.svd(cov)
    v = vt.T
    r = v @ u.T
    if np.linalg.det(r) <= 0:
        v[:, 2] *= -1
        r = v @ u.T
    T = np.eye(4)
    T[:3, :3] = r
    T[:3, 3] = cq - r @ cp
    return T


def pairs_rigid(p, q, perm):
    w = perm.sum(1)
    if w.sum() < 3:
        return np.eye(4)
    return rigid(p, perm @ q, w)


def direction(net, p, q):
    moved = p.copy()
    for it in range(ROUNDS):
        with torch.no_grad():
            s = net.match(torch.from_numpy(moved)[None], torch.from_numpy(q)[None])[0].numpy()
        perm = assign(s)
        if it + 1 < ROUNDS:
            T = pairs_rigid(moved, q, perm)
            moved = moved @ T[:3, :3].T + T[:3, 3]
    return perm


def labels(p, q, T):  # mutual, then free one-sided nearest neighbours nearer than LABEL_DIST
    moved = p @ T[:3, :3].T + T[:3, 3]
    d = np.sqrt(((moved[:, None] - q[None]) ** 2).sum(-1))
    ns, nt = d.argmin(1), d.argmin(0)
    ds, dt = d.min(1), d.min(0)
    perm = np.zeros_like(d)
    for i in range(len(p)):
        if nt[ns[i]] == i and ds[i] < LABEL_DIST:
            perm[i, ns[i]] = 1
    for i in range(len(p)):
        if perm[i].sum() == 0 and perm[:, ns[i]].sum() == 0 and ds[i] < LABEL_DIST:
            perm[i, ns[i]] = 1
    for j in range(len(q)):
        if perm[:, j].sum() == 0 and perm[nt[j]].sum() == 0 and dt[j] < LABEL_DIST:
            perm[nt[j], j] = 1
    return perm


# --------------------------------------------------------------------------- weights and pairs


def fill(net, seed):
    g = torch.Generator().manual_seed(seed)
    sd = net.state_dict()
    for key, t in sd.items():
        if key.endswith("num_batches_tracked"):
            continue
        r = torch.randn(t.shape, generator=g, dtype=torch.float64)
        if key.endswith("running_mean"):
            v = 0.1 * r
        elif key.endswith("running_var"):
            v = 1 + 0.5 * r * r
        elif key.startswith("InstNorm_layer") and key.endswith("weight"):
            v = 4 + 0.1 * r
        elif key.endswith(".A"):
            v = torch.eye(t.shape[0], dtype=torch.float64) + r / math.sqrt(t.shape[0])
        elif t.dim() >= 2:
            v = r / math.sqrt(t[0].numel())
        elif key.endswith("weight") or key.endswith("a_2"):
            v = 1 + 0.1 * r
        else:
            v = 0.1 * r
        t.copy_(v.float().double())  # float32 values, as the authors' files hold


def rotation(axis, angle):
    a = np.asarray(axis, float)
    a /= np.linalg.norm(a)
    k = np.array([[0, -a[2], a[1]], [a[2], 0, -a[0]], [-a[1], a[0], 0]])
    return np.eye(3) + math.sin(angle) * k + (1 - math.cos(angle)) * k @ k


CASES = [  # name, N, M, seed; N == M: the target is the source moved and shuffled
    ("same_size", 40, 40, 1),
    ("different_size", 48, 35, 2),
]


def case_pair(n, m, seed):
    rng = np.random.default_rng(seed)
    src = rng.uniform(-0.5, 0.5, (n, 3))
    T = np.eye(4)
    T[:3, :3] = rotation([1, 2, 2], 0.4)
    T[:3, 3] = [0.1, -0.2, 0.05]
    base = src[rng.permutation(n)] if n == m else np.concatenate([src[: min(n, m)], rng.uniform(-0.5, 0.5, (max(0, m - n), 3))])[:m]
    tgt = base @ T[:3, :3].T + T[:3, 3] + rng.normal(0, 0.01, (m, 3))
    return src, tgt, T


def write(out_dir, divisor):
    torch.set_default_dtype(torch.float64)
    torch.set_num_threads(1)
    net = Net(divisor)
    fill(net, 7)
    net.eval()
    os.makedirs(out_dir, exist_ok=True)
    torch.save({k: v.float() if v.is_floating_point() else v for k, v in net.state_dict().items()}, os.path.join(out_dir, "rgm.pth"))
    cases = []
    for name, n, m, seed in CASES:
        src, tgt, T_gt = case_pair(n, m, seed)
        with torch.no_grad():
            s = net.match(torch.from_numpy(src)[None], torch.from_numpy(tgt)[None])[0]
        gt = torch.from_numpy(labels(src, tgt, T_gt))
        loss = F.binary_cross_entropy(s, gt, reduction="sum").item() / n
        perm = direction(net, src, tgt) * direction(net, tgt, src).T
        T = pairs_rigid(src, tgt, perm)
        cases.append({"name": name, "source": src.tolist(), "target": tgt.tolist(),
                      "T_gt": T_gt.tolist(), "s": s.numpy().ravel().tolist(),
                      "loss": loss, "labels": int(gt.sum().item()),
                      "pairs": int(perm.sum()), "T": T.tolist()})
    with open(os.path.join(out_dir, "expected.json"), "w") as f:
        json.dump({"divisor": divisor, "parameters": sum(p.numel() for p in net.parameters()),
                   "keys": len(net.state_dict()), "cases": cases}, f)


if __name__ == "__main__":
    if len(sys.argv) == 4 and sys.argv[1] == "write":
        write(sys.argv[2], int(sys.argv[3]))
    else:
        sys.exit(__doc__)
