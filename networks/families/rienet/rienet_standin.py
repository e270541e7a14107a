#!/usr/bin/env python3
"""Stand-in for RIENet (Shen et al., AAAI 2022; supersyq/RIENet) in PyTorch, for the parity test
networks/families/rienet/rienet_test.cpp. Written here from a reading of the authors' model.py and
utils.py: the same module tree and state-dict keys as their RIENET (emb_nn, single_point_embed,
forwards.weight_function, forwards.fuse), and an independent forward pass of their inference (three
iterations with shared weights: light DGCNN, matching map refined by neighbourhood consensus, inlier
discriminator, weighted SVD) and of their three unsupervised losses.

Where it departs from the authors' code, on purpose and as regbench does
(networks/families/rienet/net.hpp):
  - kNN by exact float64 squared distances (stable sort: the point itself first, ties to the
    lower index); theirs takes topk of a float32 Gram-matrix distance. Equal neighbours except
    for near-ties below float32 resolution.
  - neighbourhood consensus for clouds of different sizes: sum over the k-1 non-self
    neighbours a of source point i and l of target point j of S[a, l], / (k-1); their code
    reshapes with the source's size and fails unless N == M (identical when N == M).
  - keypoints of the losses: min(n_keypoints, N) (theirs fails when N < n_keypoints).

Weights and clouds come from the formula of scripts/ogmm_reference.py (formula_fill,
formula_cloud, formula_motion), which tests/networks/formula_fixture.hpp repeats in C++; since the
formula is keyed by the tensor's name, equal outputs also show that regbench's parameter names
are the authors' keys. BatchNorm in eval mode (the authors' test mode).

Not a dependency of the product; run by hand with Debian's python3-torch:
  rienet_standin.py expected
      prints the transforms and loss terms of the test's cases in float64, and how far float32
      is from them (a conditioning check), as JSON.
  rienet_standin.py authors AUTHORS_DIR
      runs the authors' RIENET from AUTHORS_DIR (their model.py, utils.py, util.py,
      chamfer_loss.py made CPU-only, with a CPU gather_operation in pointnet2/pointnet2_utils.py)
      with the same formula weights on the equal-size cases and prints both results.
  rienet_standin.py time AUTHORS_DIR [POINTS]
      CPU time of the authors' RIENET forward (eval, no gradient, one torch thread) on a pair of
      POINTS (717) uniform random points, five runs after a warm-up; their forward also
      computes the losses, as regbench's does.
  rienet_standin.py save FILE
      torch.save of the formula-filled state dict (zip format), for regbench's reader.
  rienet_standin.py checkpoint DIR
      DIR/rienet_authors.pth in the layout of the authors' published files ({"model": state
      dict, "optimizer": Adam's state dict after one step, "epoch": int, "best_result": a numpy
      float64}), with formula weights, and DIR/rienet_reference.json: the cases' clouds and the
      stand-in's float64 transforms with those (float32-stored) weights, for
      tests/networks/authors_checkpoint_test.cpp.
"""
import json
import os
import sys
import types

import torch
import torch.nn as nn
import torch.nn.functional as F

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "..", "scripts"))
from ogmm_reference import formula_cloud, formula_fill, formula_motion  # noqa: E402

# The authors' ModelNet40 configuration (config/train.yaml).
CONFIG = dict(emb_dims=256, dim=8, iterations=3, k=5, k_nc=5, nn_margin=0.7, loss_margin=0.01,
              keypoints=256)

# --------------------------------------------------------------------------- module layout


def _conv_bn(module, conv, bn, pairs):
    """Attributes conv1..convK (bias-free 1x1) then bn1..bnK: the authors' registration order."""
    for n, (i, o) in enumerate(pairs, 1):
        setattr(module, "conv%d" % n, conv(i, o, kernel_size=1, bias=False))
    for n, (_, o) in enumerate(pairs, 1):
        setattr(module, "bn%d" % n, bn(o))


class LightDgcnn(nn.Module):
    def __init__(self, emb):
        super().__init__()
        _conv_bn(self, nn.Conv2d, nn.BatchNorm2d, [(3, 32), (32, 32), (32, 64), (64, 128), (256, emb)])


class Holder(nn.Module):
    pass


def leaky_block(i, o, kernel):
    pad = (1, 0) if kernel == (3, 1) else 0
    return [nn.Conv2d(i, o, kernel_size=kernel, padding=pad), nn.BatchNorm2d(o), nn.LeakyReLU(0.2)]


class InlierDiscriminator(nn.Module):
    def __init__(self, dim):
        super().__init__()
        self.model1 = nn.Sequential(*leaky_block(3, dim, (3, 1)), *leaky_block(dim, 2 * dim, (3, 1)))
        self.model2 = nn.Sequential(*leaky_block(2 * dim, 16, 1), *leaky_block(16, 16, 1))
        self.model3 = nn.Sequential(*leaky_block(2 * dim, 16, 1), *leaky_block(16, 16, 1))
        self.model4 = nn.Sequential(nn.Conv1d(16, 8, 1), nn.BatchNorm1d(8), nn.LeakyReLU(0.2),
                                    nn.Conv1d(8, 1, 1))


class RienetLayout(nn.Module):
    def __init__(self, emb=256, dim=8):
        super().__init__()
        self.emb_nn = Holder()
        self.emb_nn.model = LightDgcnn(emb)
        self.single_point_embed = Holder()  # built by the authors, never called
        _conv_bn(self.single_point_embed, nn.Conv1d, nn.BatchNorm1d,
                 [(3, 32), (32, 32), (32, 64), (64, 128), (128, 256)])
        self.forwards = Holder()
        self.forwards.weight_function = InlierDiscriminator(dim)
        self.forwards.fuse = Holder()  # built by the authors, never called
        _conv_bn(self.forwards.fuse, nn.Conv1d, nn.BatchNorm1d, [(512, 256), (256, 64), (64, 32)])


# ------------------------------------------------------------------------------- forward


def knn_exact(x, k):
    """x [B, N, 3] -> [B, N, k]: nearest first by float64 squared distance, stable."""
    d2 = ((x.double().unsqueeze(2) - x.double().unsqueeze(1)) ** 2).sum(3)
    return torch.sort(d2, dim=2, stable=True)[1][:, :, :k]


def gather_rows(x, idx):
    """x [B, N, C], idx [B, N, k] -> [B, N, k, C]."""
    b, n, k = idx.shape
    return torch.gather(x.unsqueeze(1).expand(b, n, x.shape[1], x.shape[2]), 2,
                        idx.unsqueeze(3).expand(b, n, k, x.shape[2]))


def features(dg, x, idx):
    """Light DGCNN on rows x [B, N, 3] with neighbours idx -> [B, N, emb]."""
    rel = (gather_rows(x, idx) - x.unsqueeze(2)).permute(0, 3, 1, 2)  # [B, 3, N, k]
    h, pooled = rel, []
    for n in range(1, 5):
        h = F.relu(getattr(dg, "bn%d" % n)(getattr(dg, "conv%d" % n)(h)))
        pooled.append(h.max(3, keepdim=True)[0])
    out = F.relu(dg.bn5(dg.conv5(torch.cat(pooled, 1))))
    return out.squeeze(3).transpose(1, 2)


def feature_distance(f, g):
    d2 = (f * f).sum(2, keepdim=True) - 2 * f @ g.transpose(1, 2) + (g * g).sum(2).unsqueeze(1)
    return d2.clamp(min=0).sqrt()


def consensus(scores, idx_s, idx_t, k):
    """nc[i, j] = sum_{a, l >= 1} scores[nbr_a(i), nbr_l(j)] / (k - 1), any N and M."""
    out = []
    for s, ns, nt in zip(scores, idx_s[:, :, 1:k], idx_t[:, :, 1:k]):
        rows = s[ns].sum(1)  # [N, M]: summed over the source neighbours
        out.append(rows[:, nt].sum(2) / (k - 1))  # summed over the target neighbours
    return torch.stack(out)


def discriminate(wf, a, b):
    """Inlier confidence from neighbourhoods a (pseudo target), b (source) [B, N, k, 3]."""
    fa = wf.model1(a.permute(0, 3, 2, 1)).permute(0, 1, 3, 2)
    fb = wf.model1(b.permute(0, 3, 2, 1)).permute(0, 1, 3, 2)
    diff = fa - fb  # [B, 2 dim, N, k]
    att = torch.softmax(wf.model3(diff), dim=3)
    pooled = (wf.model2(diff) * att).sum(3)
    return 1 - torch.tanh(wf.model4(pooled).abs()).squeeze(1)  # [B, N]


def weighted_kabsch(src, dst, w):
    """Rows src, dst [B, N, 3], weights [B, N] -> R [B, 3, 3], t [B, 3] with dst ~ R src + t."""
    ww = w.unsqueeze(2)
    cs = (src * ww).sum(1) / w.sum(1, keepdim=True)
    cd = (dst * ww).sum(1) / w.sum(1, keepdim=True)
    h = ((src - cs.unsqueeze(1)) * ww).transpose(1, 2) @ (dst - cd.unsqueeze(1))
    u, _, vh = torch.linalg.svd(h)
    v = vh.transpose(1, 2)
    d = torch.det(v @ u.transpose(1, 2))
    diag = torch.diag_embed(torch.stack([torch.ones_like(d), torch.ones_like(d), d], 1))
    r = v @ diag @ u.transpose(1, 2)
    return r, cd - (r @ cs.unsqueeze(2)).squeeze(2)


def huber_chamfer(a, b, c):
    d2 = ((a.unsqueeze(2) - b.unsqueeze(1)) ** 2).sum(3)
    hub = lambda x: torch.where(x < c, 0.5 * x * x, c * x - 0.5 * c * c)  # noqa: E731
    return hub(d2.min(2)[0]).sum() + hub(d2.min(1)[0]).sum()


def run(net, src, tgt, cfg):
    """src [B, N, 3], tgt [B, M, 3] rows -> T [B, 4, 4] and the summed loss terms."""
    dg, wf = net.emb_nn.model, net.forwards.weight_function
    b, n, _ = src.shape
    k, knc = cfg["k"], cfg["k_nc"]
    rot = torch.eye(3, dtype=src.dtype).repeat(b, 1, 1)
    trans = torch.zeros(b, 3, dtype=src.dtype)
    terms = dict(global_alignment=0.0, consensus=0.0, spatial_consistency=0.0)
    idx_t = knn_exact(tgt, max(k, knc))
    for _ in range(cfg["iterations"]):
        idx_s = knn_exact(src, max(k, knc))
        fs, ft = features(dg, src, idx_s[:, :, :k]), features(dg, tgt, idx_t[:, :, :k])
        dist = feature_distance(fs, ft)
        nc = consensus(torch.softmax(-dist, 2), idx_s, idx_t, knc)
        matching = torch.softmax(-torch.exp(cfg["nn_margin"] - nc) * dist, 2)
        corr = matching @ tgt  # [B, N, 3]
        nbr_s = idx_s[:, :, :k]
        pseudo = corr.unsqueeze(2) - gather_rows(corr, nbr_s)
        local = src.unsqueeze(2) - gather_rows(src, nbr_s)
        w = discriminate(wf, pseudo, local)
        r, t = weighted_kabsch(src, corr, w)
        # losses (the authors' LossFunction and SVDHead's spatial consistency)
        kp = torch.topk(w, min(cfg["keypoints"], n), dim=1)[1]  # [B, K]
        moved = src @ r.transpose(1, 2) + t.unsqueeze(1)
        pick = lambda x: torch.stack([xb[kb] for xb, kb in zip(x, kp)])  # noqa: E731
        sc = -torch.log(pick(matching).max(2)[0] + 1e-15).mean()
        kp_loss = ((pick(moved) - pick(corr)) ** 2).sum()
        moved_local = moved.unsqueeze(2) - gather_rows(moved, nbr_s)
        knn_loss = ((pick(moved_local) - pick(pseudo)) ** 2).sum()
        terms["consensus"] += knn_loss / knc + kp_loss
        terms["global_alignment"] += huber_chamfer(tgt, moved, cfg["loss_margin"])
        terms["spatial_consistency"] += sc
        rot, trans = r @ rot, (r @ trans.unsqueeze(2)).squeeze(2) + t
        src = moved
    out = torch.eye(4, dtype=src.dtype).repeat(b, 1, 1)
    out[:, :3, :3], out[:, :3, 3] = rot, trans
    return out, terms


# ---------------------------------------------------------------------------------- cases


def cases():
    """(name, source, target) rows in float64; see networks/families/rienet/rienet_test.cpp."""
    src = formula_cloud(2, 300, 0.0).double()
    motion = formula_motion(2).double()
    shared = src @ motion[:, :3, :3].transpose(1, 2) + motion[:, :3, 3].unsqueeze(1)
    shared = shared.flip(1)  # the same points in reverse order
    other = formula_cloud(1, 257, 1.0).double()
    other = other @ motion[:1, :3, :3].transpose(1, 2) + motion[:1, :3, 3].unsqueeze(1)
    return [("shared_points", src, shared), ("different_sizes", src[:1], other)]


def make_net(cfg, dtype):
    net = RienetLayout(cfg["emb_dims"], cfg["dim"]).to(dtype)
    formula_fill(net)
    return net.eval()


def as_list(t, digits=7):
    return [float("%.*g" % (digits, v)) for v in t.reshape(-1).tolist()]


def expected():
    """float64 results (what the test compares; float32 differs from them by up to ~1e-4 on
    these pairs, printed as float32_max_diff) and the loss terms."""
    out = {}
    nets = {dt: make_net(CONFIG, dt) for dt in (torch.float32, torch.float64)}
    for name, src, tgt in cases():
        with torch.no_grad():
            T32, _ = run(nets[torch.float32], src.float(), tgt.float(), CONFIG)
            T, terms = run(nets[torch.float64], src, tgt, CONFIG)
        out[name] = dict(T=as_list(T, 12), loss={k: float("%.12g" % v) for k, v in terms.items()},
                         float32_max_diff=float((T32.double() - T).abs().max()))
    print(json.dumps(out))


def authors_net(path):
    sys.path.insert(0, path)
    from model import RIENET  # the authors' module, made CPU-only (see the docstring)
    return RIENET(types.SimpleNamespace(n_keypoints=CONFIG["keypoints"], nn_margin=CONFIG["nn_margin"],
                                 loss_margin=CONFIG["loss_margin"], list_k1=[CONFIG["k"]] * 3,
                                 list_k2=[CONFIG["k_nc"]] * 3, emb_dims=CONFIG["emb_dims"],
                                 n_iters=CONFIG["iterations"], dim=CONFIG["dim"],
                                 dataset="modelnet40"))


def time_authors(path, points):
    import time
    torch.set_num_threads(1)
    weights = make_net(CONFIG, torch.float32).state_dict()  # formula weights
    net = authors_net(path)
    net.load_state_dict(weights, strict=True)
    net.eval()
    src = formula_cloud(1, points, 0.0).transpose(1, 2).contiguous()
    tgt = formula_cloud(1, points, 1.0).transpose(1, 2).contiguous()
    with torch.no_grad():
        net(src, tgt)
        for _ in range(5):
            wall, cpu = time.perf_counter(), time.process_time()
            net(src, tgt)
            print("wall %.3f s  cpu %.3f s" % (time.perf_counter() - wall, time.process_time() - cpu))


def authors(path):
    theirs = authors_net(path)
    mine = make_net(CONFIG, torch.float32)
    assert list(theirs.state_dict().keys()) == list(mine.state_dict().keys()), "key mismatch"
    theirs.load_state_dict(mine.state_dict(), strict=True)
    theirs.eval()
    for name, src, tgt in cases():
        if src.shape[1] != tgt.shape[1]:
            continue  # the authors' code needs N == M
        with torch.no_grad():
            r, t, gal, nc, sc = theirs(src.float().transpose(1, 2), tgt.float().transpose(1, 2))
            T, terms = run(mine, src.float(), tgt.float(), CONFIG)
        print(name, "authors R", as_list(r), "t", as_list(t))
        print(name, "authors losses", float(gal), float(nc), float(sc))
        print(name, "stand-in losses", {k: float(v) for k, v in terms.items()})
        print(name, "max |stand-in - authors| R %.3g t %.3g" % (
            (T[:, :3, :3] - r).abs().max(), (T[:, :3, 3] - t).abs().max()))


def checkpoint(out):
    import numpy as np
    os.makedirs(out, exist_ok=True)
    net = make_net(CONFIG, torch.float32).train()
    optimizer = torch.optim.Adam(net.parameters(), lr=1e-3)
    sum(p.square().sum() for p in net.parameters()).backward()
    optimizer.step()  # so the optimizer state holds tensors, as the authors' files do
    formula_fill(net)  # the weights the reference uses; Adam's state stays
    net.eval()
    torch.save({"model": net.state_dict(), "optimizer": optimizer.state_dict(), "epoch": 41,
                "best_result": np.float64(0.0123)}, os.path.join(out, "rienet_authors.pth"))
    net64 = make_net(CONFIG, torch.float32).double()  # float32-stored weights, run in float64
    ref = {"tensors": len(net.state_dict()), "cases": {}, "cases_7scenes": {}}
    # The authors' config/train7.yaml: the same widths, other neighbourhoods and margin.
    config7 = dict(CONFIG, k=8, k_nc=8, nn_margin=0.5, keypoints=768)
    for name, src, tgt in cases():
        with torch.no_grad():
            T, _ = run(net64, src, tgt, CONFIG)
            T7, _ = run(net64, src, tgt, config7)
        ref["cases"][name] = {"source": src.tolist(), "target": tgt.tolist(), "T": T.tolist()}
        ref["cases_7scenes"][name] = {"T": T7.tolist()}
    with open(os.path.join(out, "rienet_reference.json"), "w") as f:
        json.dump(ref, f)


if __name__ == "__main__":
    if len(sys.argv) == 2 and sys.argv[1] == "expected":
        expected()
    elif len(sys.argv) == 3 and sys.argv[1] == "authors":
        authors(sys.argv[2])
    elif len(sys.argv) in (3, 4) and sys.argv[1] == "time":
        time_authors(sys.argv[2], int(sys.argv[3]) if len(sys.argv) == 4 else 717)
    elif len(sys.argv) == 3 and sys.argv[1] == "save":
        torch.save(make_net(CONFIG, torch.float32).state_dict(), sys.argv[2])
    elif len(sys.argv) == 3 and sys.argv[1] == "checkpoint":
        checkpoint(sys.argv[2])
    else:
        sys.exit(__doc__)
