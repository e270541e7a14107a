#!/usr/bin/env python3
"""A PyTorch stand-in of REGTR's module layout (yewzijian/RegTR src/models/regtr.py with the
ModelNet config), written for regbench's parity test from the authors' description of each block,
not copied: its state dict has the authors' keys and shapes, and its forward is the authors'
inference with two choices fixed the same way as regbench's C++ (networks/families/regtr/net.hpp):
grid subsampling returns the voxels in increasing integer (x, y, z) order (the authors'
MinkowskiEngine order is a hash order), and a radius neighbourhood is the support points strictly
within the radius in index order, the first `limit` (pytorch3d ball_query's rule), found here by
brute force.

Usage:
  regtr_standin.py write OUT_DIR   writes, per case, OUT_DIR/<case>.pth (torch.save of
                                   {"state_dict": ..., "epoch": 0}) and OUT_DIR/cases.json
                                   (clouds, the stand-in's transform, its superpoint count)
  regtr_standin.py count           prints the parameter count of the ModelNet config
  regtr_standin.py timing N        seconds of one float32 forward on N + N points, one thread
"""
import json
import math
import os
import sys
import time

import numpy as np
import torch
import torch.nn as nn
import torch.nn.functional as F


class Cfg:
    def __init__(self, F0=512, d=256, heads=8, ff=1024, layers=6, dl=0.03, conv_radius=2.75,
                 kp_extent=2.0, limit=50):
        self.F0, self.d, self.heads, self.ff, self.layers = F0, d, heads, ff, layers
        self.dl, self.conv_radius, self.kp_extent, self.limit = dl, conv_radius, kp_extent, limit


def grid_subsample(p, dl):
    keys = np.floor(p / dl).astype(np.int64)
    uniq, inverse = np.unique(keys, axis=0, return_inverse=True)  # lexicographic (x, y, z)
    inverse = inverse.reshape(-1)
    out = np.zeros((len(uniq), 3))
    np.add.at(out, inverse, p)
    return out / np.bincount(inverse)[:, None]


def radius_neighbors(q, s, r, limit):
    d2 = ((q[:, None, :] - s[None, :, :]) ** 2).sum(-1)
    out = np.full((len(q), limit), len(s), dtype=np.int64)
    for i in range(len(q)):
        idx = np.nonzero(d2[i] < r * r)[0][:limit]
        out[i, :len(idx)] = idx
    return torch.from_numpy(out)


def inorm(x):
    # InstanceNorm1d over the points of one cloud, no affine
    return F.instance_norm(x.t().unsqueeze(0)).squeeze(0).t()


class KPConv(nn.Module):
    def __init__(self, cin, cout, radius, extent):
        super().__init__()
        self.extent = extent
        self.weights = nn.Parameter(torch.zeros(15, cin, cout))
        self.kernel_points = nn.Parameter(torch.zeros(15, 3), requires_grad=False)
        self.radius = radius

    def forward(self, q, s, nb, x):
        s = torch.cat([s, torch.full_like(s[:1], 1e6)])
        rel = s[nb] - q[:, None]                      # Q, H, 3
        dist = (rel[:, :, None] - self.kernel_points).norm(dim=-1)  # Q, H, K
        infl = (1 - dist / self.extent).clamp(min=0).permute(0, 2, 1)
        xs = torch.cat([x, torch.zeros_like(x[:1])])[nb]           # Q, H, C
        out = torch.einsum('qkh,qhc,kco->qo', infl, xs, self.weights)
        n = (xs.sum(-1) > 0).sum(-1).clamp(min=1)
        return out / n[:, None]


class Unary(nn.Module):
    def __init__(self, cin, cout, relu):
        super().__init__()
        self.mlp = nn.Linear(cin, cout, bias=False)
        self.relu = relu

    def forward(self, x):
        y = inorm(self.mlp(x))
        return F.leaky_relu(y, 0.1) if self.relu else y


class Simple(nn.Module):
    def __init__(self, cin, cout, r, e):
        super().__init__()
        self.KPConv = KPConv(cin, cout // 2, r, e)

    def forward(self, x, q, s, nb):
        return F.leaky_relu(inorm(self.KPConv(q, s, nb, x)), 0.1)


class ResnetB(nn.Module):
    def __init__(self, cin, cout, r, e, strided):
        super().__init__()
        self.strided = strided
        self.unary1 = Unary(cin, cout // 4, True) if cin != cout // 4 else nn.Identity()
        self.KPConv = KPConv(cout // 4, cout // 4, r, e)
        self.unary2 = Unary(cout // 4, cout, False)
        self.unary_shortcut = Unary(cin, cout, False) if cin != cout else nn.Identity()

    def forward(self, x, q, s, nb):
        h = self.unary1(x)
        h = F.leaky_relu(inorm(self.KPConv(q, s, nb, h)), 0.1)
        h = self.unary2(h)
        sc = x
        if self.strided:
            sc = torch.cat([x, torch.zeros_like(x[:1])])[nb].max(1)[0]
        return F.leaky_relu(h + self.unary_shortcut(sc), 0.1)


class Encoder(nn.Module):
    def __init__(self, c):
        super().__init__()
        r0, e0, F0 = c.dl * c.conv_radius, c.dl * c.kp_extent, c.F0
        self.encoder_blocks = nn.ModuleList([
            Simple(1, F0, r0, e0),
            ResnetB(F0 // 2, F0, r0, e0, False),
            ResnetB(F0, F0, r0, e0, False),
            ResnetB(F0, F0, r0, e0, True),
            ResnetB(F0, 2 * F0, 2 * r0, 2 * e0, False),
            ResnetB(2 * F0, 2 * F0, 2 * r0, 2 * e0, False)])


class CrossLayer(nn.Module):
    def __init__(self, d, heads, ff):
        super().__init__()
        self.self_attn = nn.MultiheadAttention(d, heads)
        self.multihead_attn = nn.MultiheadAttention(d, heads)
        self.linear1 = nn.Linear(d, ff)
        self.linear2 = nn.Linear(ff, d)
        self.norm1, self.norm2, self.norm3 = nn.LayerNorm(d), nn.LayerNorm(d), nn.LayerNorm(d)

    def forward(self, s, t, sp, tp):
        # pre-norm; positions added to queries, keys and values (the ModelNet config)
        def att(m, a, b):
            return m(a[:, None], b[:, None], b[:, None])[0][:, 0]
        a = self.norm1(s) + sp
        s = s + att(self.self_attn, a, a)
        b = self.norm1(t) + tp
        t = t + att(self.self_attn, b, b)
        a, b = self.norm2(s) + sp, self.norm2(t) + tp
        s, t = s + att(self.multihead_attn, a, b), t + att(self.multihead_attn, b, a)
        s = s + self.linear2(F.relu(self.linear1(self.norm3(s))))
        t = t + self.linear2(F.relu(self.linear1(self.norm3(t))))
        return s, t


class Transformer(nn.Module):
    def __init__(self, c):
        super().__init__()
        self.layers = nn.ModuleList([CrossLayer(c.d, c.heads, c.ff) for _ in range(c.layers)])
        self.norm = nn.LayerNorm(c.d)


class Decoder(nn.Module):
    def __init__(self, d):
        super().__init__()
        self.coor_mlp = nn.Sequential(nn.Linear(d, d), nn.ReLU(), nn.Linear(d, d), nn.ReLU(),
                                      nn.Linear(d, 3))
        self.conf_logits_decoder = nn.Linear(d, 1)


class Criterion(nn.Module):
    def __init__(self, d):
        super().__init__()
        self.W = nn.Parameter(torch.zeros(d, d))


class RegTRStandIn(nn.Module):
    def __init__(self, c):
        super().__init__()
        self.c = c
        self.kpf_encoder = Encoder(c)
        self.feat_proj = nn.Linear(2 * c.F0, c.d)
        self.transformer_encoder = Transformer(c)
        self.correspondence_decoder = Decoder(c.d)
        self.feature_criterion = Criterion(c.d)
        self.feature_criterion_un = Criterion(c.d)

    def pos(self, xyz):
        d = self.c.d
        f = d // 3 // 2 * 2
        i = torch.arange(f, dtype=torch.float32)
        dim_t = (10000 ** (2 * torch.div(i, 2, rounding_mode='trunc') / f)).to(xyz.dtype)
        div = (xyz * 2 * math.pi)[..., None] / dim_t
        pe = torch.stack([div[..., 0::2].sin(), div[..., 1::2].cos()], -1).reshape(len(xyz), -1)
        return F.pad(pe, (0, d - 3 * f))

    def encode(self, p0):
        c = self.c
        r0 = c.dl * c.conv_radius
        p0n = p0.numpy()
        p1n = grid_subsample(p0n, 2 * c.dl)
        p1 = torch.from_numpy(p1n).to(p0.dtype)
        nb0 = radius_neighbors(p0n, p0n, r0, c.limit)
        pool = radius_neighbors(p1n, p0n, r0, c.limit)
        nb1 = radius_neighbors(p1n, p1n, 2 * r0, c.limit)
        x = torch.ones(len(p0), 1, dtype=p0.dtype)
        args = [(p0, p0, nb0)] * 3 + [(p1, p0, pool)] + [(p1, p1, nb1)] * 2
        for blk, a in zip(self.kpf_encoder.encoder_blocks, args):
            x = blk(x, *a)
        return p1, self.feat_proj(x)

    def forward(self, src, tgt):
        ks, fs = self.encode(src)
        kt, ft = self.encode(tgt)
        ps, pt = self.pos(ks), self.pos(kt)
        for layer in self.transformer_encoder.layers:
            fs, ft = layer(fs, ft, ps, pt)
        fs, ft = self.transformer_encoder.norm(fs), self.transformer_encoder.norm(ft)
        dec = self.correspondence_decoder
        cs, ct = dec.coor_mlp(fs), dec.coor_mlp(ft)
        ws = torch.sigmoid(dec.conf_logits_decoder(fs)[:, 0])
        wt = torch.sigmoid(dec.conf_logits_decoder(ft)[:, 0])
        a, b, w = torch.cat([ks, ct]), torch.cat([cs, kt]), torch.cat([ws, wt])
        return kabsch(a, b, w), len(ks), len(kt)


def kabsch(a, b, w):
    """Weighted least-squares rotation and translation with T a ~ b (Umeyama without scale),
    written from the closed form: H = sum w (a - ca)(b - cb)^T = U S V^T, R = V diag(1, 1,
    det(V U^T)) U^T."""
    w = w / w.sum().clamp(min=1e-6)
    ca, cb = (w[:, None] * a).sum(0), (w[:, None] * b).sum(0)
    H = ((a - ca) * w[:, None]).t() @ (b - cb)
    U, S, Vh = torch.linalg.svd(H)
    V = Vh.t()
    D = torch.eye(3, dtype=a.dtype)
    D[2, 2] = torch.sign(torch.det(V @ U.t()))
    R = V @ D @ U.t()
    T = torch.eye(4, dtype=a.dtype)
    T[:3, :3], T[:3, 3] = R, cb - R @ ca
    return T


def fill(net, seed):
    g = torch.Generator().manual_seed(seed)
    with torch.no_grad():
        for name, p in net.named_parameters():
            if name.endswith('kernel_points'):
                # a centre point and 14 in the ball, like the authors' dispositions (scaled by
                # the block's radius)
                radius = 0.03 * 2.75 * (2 if '.4.' in name or '.5.' in name else 1)
                k = torch.rand(15, 3, generator=g, dtype=torch.float64) * 2 - 1
                k = k / k.norm(dim=1, keepdim=True) * (0.4 + 0.4 * torch.rand(15, 1, generator=g,
                                                                            dtype=torch.float64))
                k[0] = 0.01 * (torch.rand(3, generator=g, dtype=torch.float64) - 0.5)
                p.copy_(k * radius)
            elif name.endswith('norm1.weight') or name.endswith('norm2.weight') or \
                    name.endswith('norm3.weight') or name.endswith('norm.weight'):
                p.copy_(1 + 0.1 * torch.randn(p.shape, generator=g, dtype=torch.float64))
            elif p.dim() == 1:
                p.copy_(0.1 * torch.randn(p.shape, generator=g, dtype=torch.float64))
            else:
                fan_in = p.shape[-2] if name.endswith('KPConv.weights') else p.shape[-1]
                if name.endswith('KPConv.weights'):
                    fan_in *= 15
                p.copy_(torch.randn(p.shape, generator=g, dtype=torch.float64) /
                        math.sqrt(fan_in))


def rotation(seed):
    rng = np.random.default_rng(seed)
    q = rng.normal(size=4)
    q /= np.linalg.norm(q)
    w, x, y, z = q
    return np.array([[1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
                     [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
                     [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)]])


def cloud(seed, n):
    # points on a bumpy surface patch 0.4 wide: dense enough for 0.0825-radius neighbourhoods
    rng = np.random.default_rng(seed)
    uv = rng.uniform(-0.2, 0.2, size=(n, 2))
    z = 0.08 * np.sin(8 * uv[:, 0]) * np.cos(6 * uv[:, 1])
    return np.column_stack([uv, z])


CASES = {
    # the authors' ModelNet widths, N == M
    'modelnet': dict(cfg=dict(), n=70, m=70, seed=1),
    # regtr-small's widths with the authors' 8 heads (an import assumes 8: no tensor holds it),
    # N != M: 400 and 250 points; level-0 neighbourhoods often exceed the 50 cap
    'small_n_ne_m': dict(cfg=dict(F0=64, d=64, heads=8, ff=128, layers=2), n=400, m=250, seed=2),
}


def write(out_dir):
    torch.set_num_threads(1)
    os.makedirs(out_dir, exist_ok=True)
    cases = {}
    for name, spec in CASES.items():
        c = Cfg(**spec['cfg'])
        net = RegTRStandIn(c).double()
        fill(net, spec['seed'])
        src = cloud(10 * spec['seed'], spec['n'])
        R = rotation(spec['seed'])
        t = np.array([0.05, -0.02, 0.03])
        tgt = cloud(10 * spec['seed'], max(spec['n'], spec['m']))[:spec['m']] @ R.T + t
        with torch.no_grad():
            T, vs, vt = net(torch.from_numpy(src), torch.from_numpy(tgt))
        torch.save({'state_dict': net.state_dict(), 'epoch': 0},
                   os.path.join(out_dir, name + '.pth'))
        cases[name] = {'source': src.tolist(), 'target': tgt.tolist(),
                       'T': T.numpy().tolist(), 'superpoints': [vs, vt],
                       'parameters': sum(p.numel() for p in net.parameters())}
    with open(os.path.join(out_dir, 'cases.json'), 'w') as f:
        json.dump(cases, f)


def main():
    cmd = sys.argv[1] if len(sys.argv) > 1 else ''
    if cmd == 'write':
        write(sys.argv[2])
    elif cmd == 'count':
        print(sum(p.numel() for p in RegTRStandIn(Cfg()).parameters()))
    elif cmd == 'timing':
        torch.set_num_threads(1)
        n = int(sys.argv[2])
        net = RegTRStandIn(Cfg())
        fill(net, 1)
        net = net.float()
        src = torch.from_numpy(np.random.default_rng(0).normal(size=(n, 3)) * 0.5).float()
        tgt = src.flip(0).contiguous()
        with torch.no_grad():
            net(src, tgt)
            t0 = time.perf_counter()
            T, vs, vt = net(src, tgt)
            print(json.dumps({'seconds': time.perf_counter() - t0, 'superpoints': [vs, vt]}))
    else:
        sys.exit(__doc__)


if __name__ == '__main__':
    main()
