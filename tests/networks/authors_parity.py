#!/usr/bin/env python3
"""Fixtures for tests/networks/authors_checkpoint_test.cpp: the authors' module layouts in PyTorch,
their state dicts saved with torch.save in both formats, and an independent forward pass.

Run by the test with Debian's python3-torch:
  authors_parity.py make OUT_DIR
      writes, for DeepGMR RRI (k 20, d_model 1024, J 16), DeepGMR xyz (d_model 128, J 8) and a
      small OGMM GMMReg (emb 32), <case>_legacy.pth (torch.save(..., _use_new_zipfile_
      serialization=False), the pre-1.6 stream DeepGMR's releases use) and <case>_zip.pth, plus
      reference.json: the pair, and this script's T, gamma, pi and mu of the source cloud.
  authors_parity.py compare A.pth B.pth deepgmr|ogmm|CASE
      loads B strictly (load_state_dict(strict=True)) into the authors' module of that layout
      and checks that A and B hold the same keys and bit-identical tensors; prints "identical".

DeepGMR: the module tree (backbone.encoder / backbone.decoder of Conv1d-BN-ReLU Sequentials),
gmm_params (3x3 isotropic covariances) and gmm_register (SVD of the pi-weighted cross
covariance times Sigma_t^-1) follow the reading of wentaoyuan/deepgmr's model.py in
docs/learned-methods.md; RRI follows its CUDA kernel's orientation. Written for this test.
OGMM: the layout of gfmei/ogmm's GMMReg (emd, proj, overlap, conv1, conv2, pos, sattn1, cattn,
sattn2) is built here as bare modules for the state dict; the forward pass is
scripts/ogmm_reference.py's Ogmm (a PyTorch implementation independent of the C++), whose
weights are set from the authors'-layout state dict through the renaming written below
(independently of networks/checkpoint/authors_checkpoint.cpp). FPS starts draw from torch's global generator
seeded with OGMM_SEED, which the C++ test seeds identically (torch::manual_seed).

Weights: PyTorch's default initialisation under torch.manual_seed(case seed) (DeepGMR's last
conv x30, for peaked assignments); BatchNorm affine U(0.5, 1.5) / N(0, 0.1^2), running
means N(0, 0.1^2), running variances U(0.5, 1.5) and num_batches_tracked 7, all in eval mode.
"""
import json
import math
import os
import sys

import torch
import torch.nn as nn
import torch.nn.functional as F

OGMM_SEED = 1234

# --------------------------------------------------------------------------- DeepGMR layout


def conv_bn_relu(i, o):
    return nn.Sequential(nn.Conv1d(i, o, kernel_size=1, bias=False), nn.BatchNorm1d(o), nn.ReLU())


class PointNetSeg(nn.Module):
    def __init__(self, d_in, d_model, j):
        super().__init__()
        self.encoder = nn.Sequential(conv_bn_relu(d_in, 64), conv_bn_relu(64, 128),
                                     conv_bn_relu(128, 256), conv_bn_relu(256, d_model))
        self.decoder = nn.Sequential(conv_bn_relu(2 * d_model, 512), conv_bn_relu(512, 256),
                                     conv_bn_relu(256, 128), nn.Conv1d(128, j, kernel_size=1))

    def forward(self, x):  # [B, C, N] -> logits [B, N, J]
        loc = self.encoder(x)
        glob = loc.max(dim=2, keepdim=True)[0].expand_as(loc)
        return self.decoder(torch.cat([loc, glob], 1)).transpose(1, 2)


def rri(xyz, k):
    """[B, N, 3] -> [B, 4k, N], in float64 then float32, the GPU kernel's phi orientation."""
    feats = []
    for cloud in xyz.double():
        c = cloud - cloud.mean(0, keepdim=True)
        d2 = ((c.unsqueeze(1) - c.unsqueeze(0)) ** 2).sum(2)
        nbr = d2.argsort(dim=1)[:, 1:k + 1]  # drop self
        q = c[nbr]  # [N, k, 3]
        rp = c.norm(dim=1)  # [N]
        ph = c / rp.unsqueeze(1)
        rq = q.norm(dim=2)  # [N, k]
        cos = ((q * ph.unsqueeze(1)).sum(2) / rq).clamp(-1.0, 1.0)
        theta = torch.acos(cos)
        tang = q - cos.unsqueeze(2) * c.unsqueeze(1)  # scaled by |p|, as the original
        tj = tang.unsqueeze(2).expand(-1, -1, k, -1)
        tm = tang.unsqueeze(1).expand(-1, k, -1, -1)
        crs = torch.cross(tj, tm, dim=3)
        psi = torch.atan2((crs * ph.view(-1, 1, 1, 3)).sum(3), (tj * tm).sum(3))
        psi = torch.where(psi < 0, psi + 2 * math.pi, psi)
        eye = torch.eye(k, dtype=torch.bool).unsqueeze(0)
        phi = psi.masked_fill(eye, float("inf")).min(dim=2)[0]
        f = torch.stack([rp.unsqueeze(1).expand(-1, k), rq, theta, phi], dim=2)  # [N, k, 4]
        feats.append(f.reshape(c.shape[0], 4 * k).T)
    return torch.stack(feats).float()


class DeepGMRLayout(nn.Module):
    def __init__(self, use_rri, k=20, d_model=1024, j=16):
        super().__init__()
        self.use_rri, self.k = use_rri, k
        self.backbone = PointNetSeg(4 * k if use_rri else 3, d_model, j)

    def gamma(self, pts):
        x = rri(pts, self.k) if self.use_rri else (pts - pts.mean(1, keepdim=True)).transpose(1, 2)
        return F.softmax(self.backbone(x), dim=2)


def gmm_params(gamma, pts):
    pi = gamma.mean(1)
    npi = pi * gamma.shape[1]
    mu = gamma.transpose(1, 2) @ pts / npi.unsqueeze(2)
    diff = pts.unsqueeze(2) - mu.unsqueeze(1)
    var = ((diff ** 2).sum(3) * gamma).sum(1) / npi  # [B, J]: trace of the scatter
    sigma = var.unsqueeze(2).unsqueeze(3) * torch.eye(3).view(1, 1, 3, 3)
    return pi, mu, sigma


def gmm_register(pi_s, mu_s, mu_t, sigma_t):
    c_s = pi_s.unsqueeze(1) @ mu_s
    c_t = pi_s.unsqueeze(1) @ mu_t
    m = ((pi_s.unsqueeze(2) * (mu_s - c_s)).unsqueeze(3) @ (mu_t - c_t).unsqueeze(2)
         @ torch.inverse(sigma_t)).sum(1)
    u, _, v = torch.svd(m)
    s = torch.eye(3).repeat(m.shape[0], 1, 1)
    s[:, 2, 2] = torch.det(v @ u.transpose(1, 2))
    r = v @ s @ u.transpose(1, 2)
    t = c_t.transpose(1, 2) - r @ c_s.transpose(1, 2)
    out = torch.eye(4).repeat(m.shape[0], 1, 1)
    out[:, :3, :3], out[:, :3, 3:] = r, t
    return out


def deepgmr_forward(net, src, tgt):
    with torch.no_grad():
        gs, gt = net.gamma(src), net.gamma(tgt)
        pi_s, mu_s, _ = gmm_params(gs, src)
        _, mu_t, sig_t = gmm_params(gt, tgt)
        return gmm_register(pi_s, mu_s, mu_t, sig_t), gs, pi_s, mu_s

# ------------------------------------------------------------------------------ OGMM layout


class CONVLayout(nn.Module):
    """gfmei/ogmm's CONV: net = conv, bn, relu, [conv, bn, relu,] conv."""

    def __init__(self, i, o, h, three):
        super().__init__()
        mods = [nn.Conv1d(i, h, 1), nn.BatchNorm1d(h), nn.ReLU()]
        if three:
            mods += [nn.Conv1d(h, h, 1), nn.BatchNorm1d(h), nn.ReLU()]
        self.net = nn.Sequential(*(mods + [nn.Conv1d(h, o, 1)]))


class DGCNNLayout(nn.Module):
    def __init__(self, emb):
        super().__init__()
        for n, (i, o) in enumerate([(6, 64), (64, 64), (64, 128), (128, 256), (512, emb)], 1):
            setattr(self, "conv%d" % n, nn.Conv2d(i, o, 1, bias=False))
        for n, o in enumerate([64, 64, 128, 256, emb], 1):
            setattr(self, "bn%d" % n, nn.BatchNorm2d(o))


class PosLayout(nn.Module):
    def __init__(self, d):
        super().__init__()
        lrelu = lambda: nn.LeakyReLU(0.2)
        self.conv_dis = nn.Sequential(nn.Conv1d(1, 64, 1, bias=False), nn.BatchNorm1d(64), lrelu(),
                                      nn.Conv1d(64, d // 2, 1, bias=False), nn.BatchNorm1d(d // 2),
                                      lrelu())
        self.conv_ang1 = nn.Sequential(nn.Conv2d(1, 64, 1, bias=False), nn.BatchNorm2d(64), lrelu())
        self.conv_ang2 = nn.Sequential(nn.Conv1d(64, d // 2, 1, bias=False), nn.BatchNorm1d(d // 2),
                                       lrelu())
        self.conv = nn.Sequential(nn.Conv1d(d, d, 1, bias=False), nn.BatchNorm1d(d), lrelu())


class MHALayout(nn.Module):
    def __init__(self, d):
        super().__init__()
        self.merge = nn.Conv1d(d, d, 1)
        self.proj = nn.ModuleList([nn.Conv1d(d, d, 1) for _ in range(3)])


class TransformerLayout(nn.Module):
    def __init__(self, d):
        super().__init__()
        self.attn = MHALayout(d)
        self.mlp = nn.Sequential(nn.Conv1d(2 * d, 2 * d, 1), nn.InstanceNorm1d(2 * d), nn.ReLU(),
                                 nn.Conv1d(2 * d, d, 1))


class GMMRegLayout(nn.Module):
    """Module names, order and shapes of GMMReg(emb_dims, n_clusters, config)."""

    def __init__(self, emb):
        super().__init__()
        self.emd = DGCNNLayout(emb)
        self.proj = CONVLayout(emb, 1, emb // 2, False)
        self.overlap = CONVLayout(emb, 1, emb // 2, True)
        self.conv1 = CONVLayout(emb, emb, 2 * emb, True)
        self.conv2 = CONVLayout(emb + 2, emb, 2 * emb, True)
        self.pos = PosLayout(emb)
        self.sattn1 = TransformerLayout(emb)
        self.cattn = TransformerLayout(emb)
        self.sattn2 = TransformerLayout(emb)


def authors_to_reference(key):
    """gfmei/ogmm GMMReg key -> scripts/ogmm_reference.py Ogmm key."""
    three = {"0": "conv1", "1": "bn1", "3": "conv2", "4": "bn2", "6": "conv3"}
    two = {"0": "conv1", "1": "bn1", "3": "conv2"}
    head, rest = key.split(".", 1)
    if head == "emd":
        return "dgcnn." + rest
    if head in ("overlap", "conv1", "conv2", "proj"):
        layer, tail = rest[len("net."):].split(".", 1)
        name = {"overlap": "conv3_o", "conv1": "conv3_a", "conv2": "conv3_b", "proj": "proj"}[head]
        return name + "." + (two if head == "proj" else three)[layer] + "." + tail
    if head in ("sattn1", "cattn", "sattn2"):
        name = {"sattn1": "att_s1", "cattn": "att_c", "sattn2": "att_s2"}[head]
        return name + "." + (rest[len("attn."):] if rest.startswith("attn.") else rest)
    if head == "pos":
        sub, tail = rest.split(".", 1)
        if sub == "conv":  # built but never called by the authors' forward
            layer, leaf = tail.split(".", 1)
            return {"0": "spe.unused_conv.", "1": "spe.unused_bn."}[layer] + leaf
        return {"conv_dis": "spe.dist.", "conv_ang1": "spe.angle_2d.",
                "conv_ang2": "spe.angle_1d."}[sub] + tail
    raise KeyError(key)


OGMM_CFG = dict(emb_dims=32, anchors=16, clusters=8, heads=2, k=10, spe_k=5, spe=True, csa=True,
                attention="clustered", osp=True, fix_overlap_index=False, gmm_iterations=10,
                sinkhorn_epsilon=0.01, sinkhorn_threshold=0.01, sinkhorn_iterations=10,
                match_temperature=0.05)


def ogmm_forward(state, src, tgt):
    sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "scripts"))
    import ogmm_reference  # noqa: E402  (independent PyTorch OGMM)
    net = ogmm_reference.Ogmm(OGMM_CFG)
    mapped = {}
    for k, v in state.items():
        mapped[authors_to_reference(k)] = v
    net.load_state_dict(mapped, strict=True)
    net.eval()
    torch.manual_seed(OGMM_SEED)
    with torch.no_grad():
        T, aux = net(src, tgt)
    gamma = aux["gam_p"]
    return T, gamma, gamma.mean(1), aux["mu_p"]

# ---------------------------------------------------------------------------------- fixtures


def fill(module, seed):
    torch.manual_seed(seed)
    for m in module.modules():
        if isinstance(m, (nn.Conv1d, nn.Conv2d)):
            m.reset_parameters()
        if isinstance(m, (nn.BatchNorm1d, nn.BatchNorm2d)):
            with torch.no_grad():
                m.weight.uniform_(0.5, 1.5)
                m.bias.normal_(0.0, 0.1)
                m.running_mean.normal_(0.0, 0.1)
                m.running_var.uniform_(0.5, 1.5)
                m.num_batches_tracked.fill_(7)
    module.eval()


def cloud(n, seed):
    g = torch.Generator().manual_seed(seed)
    return torch.rand(1, n, 3, generator=g) - 0.5


def rotate(pts, angle, t):
    axis = torch.tensor([0.3, -0.5, 0.8])
    axis = axis / axis.norm()
    kx = torch.tensor([[0, -axis[2], axis[1]], [axis[2], 0, -axis[0]], [-axis[1], axis[0], 0]])
    r = torch.eye(3) + math.sin(angle) * kx + (1 - math.cos(angle)) * kx @ kx
    return pts @ r.T + torch.tensor(t)


def tolist(t):
    return t.detach().double().tolist()


def make(out):
    os.makedirs(out, exist_ok=True)
    src = cloud(128, 1)
    tgt = rotate(src, 0.7, [0.1, -0.05, 0.2]) + 0.002 * torch.randn(1, 128, 3, generator=torch.Generator().manual_seed(2))
    ref = {"source": tolist(src[0]), "target": tolist(tgt[0]), "cases": {}}
    cases = [("deepgmr_rri", "deepgmr", DeepGMRLayout(True, 20, 1024, 16)),
             ("deepgmr_xyz", "deepgmr", DeepGMRLayout(False, 20, 128, 8)),
             ("ogmm_small", "ogmm", GMMRegLayout(OGMM_CFG["emb_dims"]))]
    for seed, (name, family, net) in enumerate(cases, 10):
        fill(net, seed)
        if family == "deepgmr":  # peaked assignments, so gamma's check sees more than 1/J
            with torch.no_grad():
                net.backbone.decoder[3].weight.mul_(30.0)
        sd = net.state_dict()
        torch.save(sd, os.path.join(out, name + "_legacy.pth"), _use_new_zipfile_serialization=False)
        torch.save(sd, os.path.join(out, name + "_zip.pth"))
        if family == "deepgmr":
            T, gamma, pi, mu = deepgmr_forward(net, src, tgt)
        else:
            T, gamma, pi, mu = ogmm_forward(sd, src, tgt)
        ref["cases"][name] = {"from": family, "T": tolist(T[0]), "gamma": tolist(gamma[0]),
                              "pi": tolist(pi[0]), "mu": tolist(mu[0]),
                              "tensors": len(sd), "ogmm": OGMM_CFG if family == "ogmm" else None}
    # A state dict of another network and a random (non-torch) pickle, for refusals.
    torch.save(nn.Sequential(nn.Linear(3, 4)).state_dict(), os.path.join(out, "other_net.pth"))
    import pickle
    with open(os.path.join(out, "random.pickle"), "wb") as f:
        pickle.dump({"a": [1, 2.5, "x"], "b": (None, True)}, f, protocol=2)
    torch.jit.save(torch.jit.script(nn.Linear(3, 4)), os.path.join(out, "torchscript.pth"))
    ref["ogmm_seed"] = OGMM_SEED
    import hashlib
    ref["sha256"] = {f: hashlib.sha256(open(os.path.join(out, f), "rb").read()).hexdigest()
                     for f in sorted(os.listdir(out)) if f.endswith(".pth")}
    with open(os.path.join(out, "reference.json"), "w") as f:
        json.dump(ref, f)


def compare(a, b, layout):
    sa, sb = torch.load(a), torch.load(b)
    if list(sa.keys()) != list(sb.keys()):
        print("keys differ:", sorted(set(sa) ^ set(sb)))
        return 1
    for k in sa:
        if sa[k].dtype != sb[k].dtype or sa[k].shape != sb[k].shape or not torch.equal(sa[k], sb[k]):
            print("tensor differs:", k)
            return 1
    if layout == "ogmm":
        net = GMMRegLayout(sa["emd.conv5.weight"].shape[0])
    else:
        w = sa["backbone.encoder.0.0.weight"]
        net = DeepGMRLayout(w.shape[1] != 3, w.shape[1] // 4, sa["backbone.encoder.3.0.weight"].shape[0],
                            sa["backbone.decoder.3.weight"].shape[0])
    net.load_state_dict(sb, strict=True)
    print("identical", len(sa))
    return 0


if __name__ == "__main__":
    if sys.argv[1] == "make":
        make(sys.argv[2])
    elif sys.argv[1] == "compare":
        sys.exit(compare(sys.argv[2], sys.argv[3], sys.argv[4]))
