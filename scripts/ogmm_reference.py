#!/usr/bin/env python3
"""Independent PyTorch implementation of regbench's OGMM and DeepGMR, for parity fixtures.

Builds DGCNN, the SuperGlue-style attention, the whole OGMM forward/loss and DeepGMR (the OGMM
paper's variant on DGCNN features, and the original PointNet on centred xyz or RRI features)
in PyTorch with the same module names as networks/layers/layers.cpp, networks/families/ogmm/net.cpp and
networks/families/deepgmr/net.cpp, sets every parameter and buffer from a deterministic formula (no RNG), runs
them on deterministic inputs and prints the outputs as JSON. networks/families/ogmm/ogmm_test.cpp,
tests/networks/layers_test.cpp and networks/families/deepgmr/deepgmr_test.cpp pin the C++ outputs to these
numbers. The DeepGMR part is written from the model's description (docs/learned-methods.md,
"DeepGMR"), not from networks/families/deepgmr/net.cpp.

Not a dependency of the product: run it by hand with Debian's python3-torch when a fixture
changes:  /usr/bin/python3 scripts/ogmm_reference.py

Formula for a tensor named `name` with flattened index i (phase from the name's characters; the
quadratic term keeps weight matrices full rank):
  phase = 0.01 * (sum_{k} (k + 1) * ord(name[k]) mod 997),  s = sin(0.37 i + 0.0013 i^2 + phase)
  conv weights (>= 2 dims): s / sqrt(fan_in)
  1-dim `*.weight` (norm scales): 1 + 0.1 s; biases: 0.1 s
  BN running_mean: 0.1 s; running_var: 1 + 0.5 s^2
Input point i of a cloud with n points and seed s:
  (0.5 sin(0.9 i + s), 0.5 cos(1.7 i + 2 s), 0.5 sin(0.23 i + 0.013 i^2 + 3 s))
"""
import json
import math

import torch
import torch.nn as nn
import torch.nn.functional as F

# ----------------------------------------------------------------------------------- blocks


def conv1x1(i, o, bias):
    return nn.Conv1d(i, o, 1, bias=bias)


class Conv3(nn.Module):
    def __init__(self, i, o, h):
        super().__init__()
        self.conv1, self.bn1 = conv1x1(i, h, True), nn.BatchNorm1d(h)
        self.conv2, self.bn2 = conv1x1(h, h, True), nn.BatchNorm1d(h)
        self.conv3 = conv1x1(h, o, True)

    def forward(self, x):
        x = F.relu(self.bn1(self.conv1(x)))
        x = F.relu(self.bn2(self.conv2(x)))
        return self.conv3(x)


class Conv2(nn.Module):
    def __init__(self, i, o, h):
        super().__init__()
        self.conv1, self.bn1 = conv1x1(i, h, True), nn.BatchNorm1d(h)
        self.conv2 = conv1x1(h, o, True)

    def forward(self, x):
        return self.conv2(F.relu(self.bn1(self.conv1(x))))


def knn(x, k):
    inner = -2 * torch.matmul(x.transpose(2, 1), x)
    xx = torch.sum(x ** 2, dim=1, keepdim=True)
    return (-xx - inner - xx.transpose(2, 1)).topk(k=k, dim=-1)[1]


def edge_features(x, idx):
    b, c, n = x.shape
    k = idx.shape[2]
    rows = x.transpose(2, 1).contiguous()
    flat = (idx + torch.arange(b).view(-1, 1, 1) * n).view(-1)
    nb = rows.view(b * n, c)[flat, :].view(b, n, k, c)
    centre = rows.view(b, n, 1, c).expand_as(nb)
    return torch.cat((nb - centre, centre), dim=3).permute(0, 3, 1, 2)


class Dgcnn(nn.Module):
    def __init__(self, emb, k):
        super().__init__()
        self.k = k
        widths = [(6, 64), (64, 64), (64, 128), (128, 256), (512, emb)]
        for j, (i, o) in enumerate(widths, 1):
            setattr(self, f"conv{j}", nn.Conv2d(i, o, 1, bias=False))
            setattr(self, f"bn{j}", nn.BatchNorm2d(o))

    def forward(self, xyz):
        x = edge_features(xyz, knn(xyz, self.k))
        pooled = []
        for j in range(1, 5):
            x = F.relu(getattr(self, f"bn{j}")(getattr(self, f"conv{j}")(x)))
            pooled.append(x.max(dim=-1, keepdim=True)[0])
        x = torch.cat(pooled, dim=1)
        return F.relu(self.bn5(self.conv5(x))).squeeze(-1)


class Attention(nn.Module):
    """SuperGlue AttentionalPropagation with the message MLP flattened into this module."""

    def __init__(self, d, heads):
        super().__init__()
        self.heads = heads
        self.merge = conv1x1(d, d, True)
        self.proj = nn.ModuleList([conv1x1(d, d, True) for _ in range(3)])
        self.mlp = nn.Sequential(conv1x1(2 * d, 2 * d, True), nn.InstanceNorm1d(2 * d), nn.ReLU(),
                                 conv1x1(2 * d, d, True))

    def forward(self, x, source):
        b, dim = x.shape[0], x.shape[1] // self.heads
        q, k, v = [l(t).view(b, dim, self.heads, -1)
                   for l, t in zip(self.proj, (x, source, source))]
        prob = F.softmax(torch.einsum("bdhn,bdhm->bhnm", q, k) / dim ** 0.5, dim=-1)
        msg = torch.einsum("bhnm,bdhm->bdhn", prob, v).contiguous().view(b, dim * self.heads, -1)
        return self.mlp(torch.cat([x, self.merge(msg)], dim=1))


class Spe(nn.Module):
    def __init__(self, out, k):
        super().__init__()
        self.k = k
        half = out // 2
        self.dist = nn.Sequential(conv1x1(1, 64, False), nn.BatchNorm1d(64), nn.LeakyReLU(0.2),
                                  conv1x1(64, half, False), nn.BatchNorm1d(half), nn.LeakyReLU(0.2))
        self.angle_2d = nn.Sequential(nn.Conv2d(1, 64, 1, bias=False), nn.BatchNorm2d(64),
                                      nn.LeakyReLU(0.2))
        self.angle_1d = nn.Sequential(conv1x1(64, half, False), nn.BatchNorm1d(half),
                                      nn.LeakyReLU(0.2))
        self.unused_conv = conv1x1(out, out, False)
        self.unused_bn = nn.BatchNorm1d(out)

    def forward(self, xyz):
        radial = xyz - xyz.mean(2, keepdim=True)
        dist = self.dist((radial ** 2).sum(1, keepdim=True))
        nb = edge_features(xyz, knn(xyz, self.k))[:, :3]
        cos = F.cosine_similarity(nb, radial.unsqueeze(-1).expand_as(nb), dim=1)
        angle = self.angle_2d(cos.unsqueeze(1)).max(dim=-1)[0]
        return torch.cat([dist, self.angle_1d(angle)], dim=1)


def fps_loop(xyz, distance, farthest, n):
    b = xyz.shape[0]
    chosen = torch.empty(b, n, dtype=torch.long)
    rows = torch.arange(b)
    for i in range(n):
        chosen[:, i] = farthest
        centre = xyz.permute(0, 2, 1)[rows, farthest].unsqueeze(2)
        distance = torch.minimum(distance, ((xyz - centre) ** 2).sum(1))
        farthest = distance.max(1)[1]
    return chosen


def fps_random(xyz, n):
    start = torch.randint(xyz.shape[2], (xyz.shape[0],), dtype=torch.long)
    return fps_loop(xyz, torch.full((xyz.shape[0], xyz.shape[2]), 1e10), start, n)


def fps_centroid(xyz, n):
    distance = ((xyz - xyz.mean(2, keepdim=True)) ** 2).sum(1)
    return fps_loop(xyz, distance, distance.max(1)[1], n)


def gather_columns(x, idx):
    return torch.gather(x, 2, idx.unsqueeze(1).expand(x.shape[0], x.shape[1], idx.shape[1]))


def log_sinkhorn(cost, p, q, eps, thr, iters):
    u, v = torch.zeros_like(p), torch.zeros_like(q)
    lp, lq = torch.log(p + 1e-8), torch.log(q + 1e-8)

    def kern(uu, vv):
        return (-cost + uu.unsqueeze(2) + vv.unsqueeze(1)) / eps

    for _ in range(iters):
        u0, v0 = u, v
        u = u + eps * (lp - torch.logsumexp(kern(u, v), 2))
        v = v + eps * (lq - torch.logsumexp(kern(u, v), 1))
        if ((u - u0).abs().sum(1) + (v - v0).abs().sum(1)).mean().item() < thr:
            break
    return torch.exp(kern(u, v))


def cluster_averages(gamma, x):
    return torch.bmm(gamma.transpose(1, 2), x) / (gamma.sum(1).unsqueeze(2) + 1e-5)


def fit_gmm(xyz, overlap, j, cfg):
    with torch.no_grad():
        w = overlap / overlap.sum(1, keepdim=True).clamp_min(1e-4)
        q = torch.full((1, j), 1.0 / j)
        mu = torch.gather(xyz, 1, fps_centroid(xyz.transpose(1, 2), j).unsqueeze(2).expand(-1, -1, 3))
        for _ in range(cfg["gmm_iterations"]):
            cost = torch.cdist(xyz, mu)
            plan = torch.cat([log_sinkhorn(cost[b:b + 1], w[b:b + 1], q, cfg["sinkhorn_epsilon"],
                                           cfg["sinkhorn_threshold"], cfg["sinkhorn_iterations"])
                              for b in range(xyz.shape[0])])
            plan = torch.nan_to_num(plan, 0.0, 0.0, 0.0)
            gamma = plan / plan.sum(2, keepdim=True).clamp_min(1e-3)
            mu = cluster_averages(gamma, xyz)
    return gamma, mu


def kabsch(src, dst):
    sm, dm = src.mean(1, keepdim=True), dst.mean(1, keepdim=True)
    H = torch.bmm((src - sm).transpose(1, 2), dst - dm) + 1e-5 * torch.eye(3)
    U, S, Vh = torch.linalg.svd(H, full_matrices=False)
    V = Vh.transpose(1, 2)
    sign = torch.where(torch.det(torch.bmm(V, U.transpose(1, 2))) < 0, -1.0, 1.0)
    V = torch.cat([V[:, :, :2], V[:, :, 2:] * sign.view(-1, 1, 1)], 2)
    R = torch.bmm(V, U.transpose(1, 2))
    t = dm.transpose(1, 2) - torch.bmm(R, sm.transpose(1, 2))
    bottom = torch.tensor([0.0, 0.0, 0.0, 1.0]).view(1, 1, 4).expand(src.shape[0], 1, 4)
    return torch.cat([torch.cat([R, t], 2), bottom], 1)


# ------------------------------------------------------------------------------------ OGMM


class Ogmm(nn.Module):
    def __init__(self, cfg):
        super().__init__()
        self.cfg = cfg
        d, h = cfg["emb_dims"], cfg["heads"]
        self.dgcnn = Dgcnn(d, cfg["k"])
        if cfg["spe"]:
            self.spe = Spe(d, cfg["spe_k"])
        if cfg["csa"]:
            self.att_s1 = Attention(d, h)
        self.conv3_a = Conv3(d, d, 2 * d)
        self.att_c = Attention(d, h)
        if cfg["osp"]:
            self.proj = Conv2(d, 1, d // 2)
            self.conv3_b = Conv3(d + 2, d, 2 * d)
            self.conv3_o = Conv3(d, 1, d // 2)
        if cfg["csa"]:
            self.att_s2 = Attention(d, h)

    def anchors(self, f, xyz):
        if self.cfg["attention"] == "full":
            return f
        return gather_columns(f, fps_random(xyz, min(self.cfg["anchors"], xyz.shape[2])))

    def overlap(self, gp, gq):
        S = torch.bmm(F.normalize(gp, dim=1).transpose(1, 2), F.normalize(gq, dim=1))
        zp, zq = self.proj(gp), self.proj(gq)
        row, col = F.softmax(S, 2), F.softmax(S, 1)
        code = not self.cfg["fix_overlap_index"] and gp.shape[2] == gq.shape[2]
        wp = torch.bmm(row, (zp if code else zq).transpose(1, 2))
        wq = torch.bmm(col.transpose(1, 2), (zq if code else zp).transpose(1, 2))

        def head(g, w, z):
            return torch.sigmoid(self.conv3_o(self.conv3_b(torch.cat([g, w.transpose(1, 2), z], 1)))).squeeze(1)

        return head(gp, wp, zp), head(gq, wq, zq)

    def forward(self, src, tgt):
        c = self.cfg
        p, q = src.transpose(1, 2).contiguous(), tgt.transpose(1, 2).contiguous()
        fp, fq = self.dgcnn(p), self.dgcnn(q)
        xp = fp + self.spe(p) if c["spe"] else fp
        xq = fq + self.spe(q) if c["spe"] else fq
        if c["csa"]:
            ap, aq = self.anchors(fp, p), self.anchors(fq, q)
            xp = self.att_s1(xp, ap) + xp
            xq = self.att_s1(xq, aq) + xq
        xp, xq = self.conv3_a(xp), self.conv3_a(xq)
        bp, bq = self.anchors(xp, p), self.anchors(xq, q)
        gp, gq = self.att_c(xp, bq) + xp, self.att_c(xq, bp) + xq
        if c["osp"]:
            op, oq = self.overlap(gp, gq)
        else:
            op, oq = torch.ones(p.shape[0], p.shape[2]), torch.ones(q.shape[0], q.shape[2])
        if c["csa"]:
            fsp = self.att_s2(gp, self.anchors(gp, p)) + gp
            fsq = self.att_s2(gq, self.anchors(gq, q)) + gq
        else:
            fsp, fsq = gp, gq
        gam_p, mu_p = fit_gmm(src, op.detach(), min(c["clusters"], p.shape[2]), c)
        gam_q, mu_q = fit_gmm(tgt, oq.detach(), min(c["clusters"], q.shape[2]), c)
        nu_p = cluster_averages(gam_p, fsp.transpose(1, 2))
        nu_q = cluster_averages(gam_q, fsq.transpose(1, 2))
        cos = torch.bmm(F.normalize(nu_p, dim=2), F.normalize(nu_q, dim=2).transpose(1, 2))
        matched = torch.bmm(F.softmax(cos / c["match_temperature"], 2), mu_q)
        T = kabsch(mu_p, matched)
        return T, dict(op=op, oq=oq, mu_p=mu_p, mu_q=mu_q, nu_p=nu_p, nu_q=nu_q, fsp=fsp, fsq=fsq,
                       gam_p=gam_p, gam_q=gam_q)

    def cluster_loss(self, xyz, mu, nu, f):
        b, j = mu.shape[0], mu.shape[1]
        with torch.no_grad():
            nearest = ((mu.unsqueeze(2) - xyz.unsqueeze(1)) ** 2).sum(3).min(2)[1]
        a = F.normalize(gather_columns(f, nearest).transpose(1, 2), dim=2)
        z = torch.cat([a, F.normalize(nu, dim=2)], 1)
        logits = (torch.bmm(z, z.transpose(1, 2)) / self.cfg["nt_xent_temperature"]).masked_fill(
            torch.eye(2 * j, dtype=torch.bool).unsqueeze(0), float("-inf"))
        target = torch.cat([torch.arange(j, 2 * j), torch.arange(0, j)]).repeat(b)
        return F.cross_entropy(logits.reshape(b * 2 * j, 2 * j), target)

    def loss(self, src, tgt, T_gt, ls, lt, T, aux):
        c = self.cfg
        R, t = T[:, :3, :3], T[:, :3, 3]
        terms = {}
        terms["pose"] = F.mse_loss(torch.bmm(R.transpose(1, 2), T_gt[:, :3, :3]),
                                   torch.eye(3).expand_as(R)) + F.mse_loss(t, T_gt[:, :3, 3])
        terms["clu"] = 0.5 * (self.cluster_loss(src, aux["mu_p"], aux["nu_p"], aux["fsp"]) +
                              self.cluster_loss(tgt, aux["mu_q"], aux["nu_q"], aux["fsq"]))
        terms["ovl"] = F.mse_loss(torch.cat([aux["op"], aux["oq"]], 1), torch.cat([ls, lt], 1))
        moved = torch.bmm(src, R.transpose(1, 2)) + t.unsqueeze(1)

        def welsch(frm, labels, to):
            keep = min(c["welsch_keypoints"], frm.shape[1])
            idx = labels.topk(keep, 1)[1]
            picked = torch.gather(frm, 1, idx.unsqueeze(2).expand(-1, -1, 3))
            z2 = ((picked.unsqueeze(2) - to.unsqueeze(1)) ** 2).sum(3).min(2)[0]
            return (1 - torch.exp(-z2 / (2 * c["welsch_alpha"] ** 2))).sum(1)

        terms["welsch"] = (welsch(moved, ls, tgt) + welsch(tgt, lt, moved)).mean()
        w = dict(pose=c["w_pose"], clu=c["w_clu"], ovl=c["w_ovl"], welsch=c["w_welsch"])
        terms["total"] = sum(w[k] * torch.nan_to_num(v, 0.0, 0.0, 0.0) for k, v in terms.items())
        return terms



# --------------------------------------------------------------------------------- DeepGMR


def cbr(i, o):
    """1x1 Conv1d without bias, BatchNorm1d, ReLU (children "0", "1" as the original)."""
    return nn.Sequential(nn.Conv1d(i, o, 1, bias=False), nn.BatchNorm1d(o), nn.ReLU())


def rri_features(xyz, k):
    """RRI of each cloud of xyz [B, N, 3] (GPU-kernel orientation) -> [B, 4k, N], float64 math.

    Centred cloud; per point p and its k nearest neighbours q_j (self excluded): r_p, r_q,
    theta = acos(clip(p_hat . q / r_q)), T_j = q_j - cos(theta_j) p,
    phi_j = min_{m != j} atan2((T_j x T_m) . p_hat, T_j . T_m) (+2 pi when negative)."""
    out = []
    for cloud in xyz.double():
        c = cloud - cloud.mean(0)
        n = c.shape[0]
        nbr = torch.cdist(c, c).topk(k + 1, largest=False)[1][:, 1:]
        feats = torch.empty(n, 4 * k, dtype=torch.float64)
        for a in range(n):
            p = c[a]
            rp = p.norm()
            ph = p / rp
            q = c[nbr[a]]
            rq = q.norm(dim=1)
            d = ((q @ ph) / rq).clamp(-1, 1)
            tang = q - d.unsqueeze(1) * p
            cross = torch.cross(tang.unsqueeze(1).expand(k, k, 3), tang.unsqueeze(0).expand(k, k, 3), dim=2)
            psi = torch.atan2(cross @ ph, tang @ tang.T)
            psi = torch.where(psi < 0, psi + 2 * math.pi, psi)
            psi.fill_diagonal_(float("inf"))
            feats[a] = torch.stack([rp.expand(k), rq, torch.acos(d), psi.min(1)[0]], 1).reshape(-1)
        out.append(feats.T)
    return torch.stack(out).to(xyz.dtype)


class DeepGmr(nn.Module):
    """features "dgcnn": Dgcnn(d, k) -> Conv3(d, J, hidden) ("dgcnn", "head"); "xyz"/"rri": the
    original PointNet segmentation net under "backbone.encoder" / "backbone.decoder"."""

    def __init__(self, cfg):
        super().__init__()
        self.cfg = cfg
        j = cfg["clusters"]
        if cfg["features"] == "dgcnn":
            self.dgcnn = Dgcnn(cfg["emb_dims"], cfg["dgcnn_k"])
            self.head = Conv3(cfg["emb_dims"], j, cfg["head_hidden"])
        else:
            d_in = 4 * cfg["rri_k"] if cfg["features"] == "rri" else 3
            self.backbone = nn.Module()
            self.backbone.encoder = nn.Sequential(cbr(d_in, 64), cbr(64, 128), cbr(128, 256),
                                                  cbr(256, 1024))
            self.backbone.decoder = nn.Sequential(cbr(2048, 512), cbr(512, 256), cbr(256, 128),
                                                  nn.Conv1d(128, j, 1))

    def gamma(self, xyz):
        f = self.cfg["features"]
        if f == "dgcnn":
            logits = self.head(self.dgcnn(xyz.transpose(1, 2).contiguous()))
        else:
            x = rri_features(xyz, self.cfg["rri_k"]) if f == "rri" else \
                (xyz - xyz.mean(1, keepdim=True)).transpose(1, 2)
            local = self.backbone.encoder(x)
            glob = local.max(2, keepdim=True)[0].expand_as(local)
            logits = self.backbone.decoder(torch.cat([local, glob], 1))
        return F.softmax(logits, dim=1).transpose(1, 2)  # [B, N, J]

    @staticmethod
    def mixture(gamma, xyz):
        mass = gamma.sum(1)  # [B, J]
        mu = torch.einsum("bnj,bnc->bjc", gamma, xyz) / mass.unsqueeze(2)
        sq = ((xyz.unsqueeze(2) - mu.unsqueeze(1)) ** 2).sum(3)  # [B, N, J]
        return mass / xyz.shape[1], mu, (gamma * sq).sum(1) / mass

    @staticmethod
    def register(pi_s, mu_s, mu_t, s_t):
        """Centroids weighted by pi_s, covariance weighted by pi_s / s_t, SVD with det guard."""
        c_s = torch.einsum("bj,bjc->bc", pi_s, mu_s)
        c_t = torch.einsum("bj,bjc->bc", pi_s, mu_t)
        w = pi_s / s_t
        M = torch.einsum("bj,bjr,bjc->brc", w, mu_s - c_s.unsqueeze(1), mu_t - c_t.unsqueeze(1))
        U, _, Vh = torch.linalg.svd(M)
        V = Vh.transpose(1, 2)
        D = torch.diag_embed(torch.stack([torch.ones(M.shape[0]), torch.ones(M.shape[0]),
                                          torch.det(V @ U.transpose(1, 2))], 1))
        R = V @ D @ U.transpose(1, 2)
        t = c_t - torch.einsum("brc,bc->br", R, c_s)
        T = torch.eye(4).repeat(M.shape[0], 1, 1)
        T[:, :3, :3], T[:, :3, 3] = R, t
        return T

    def forward(self, src, tgt):
        gs, gt = self.gamma(src), self.gamma(tgt)  # two calls: BN sees each cloud alone
        pi_s, mu_s, s_s = self.mixture(gs, src)
        pi_t, mu_t, s_t = self.mixture(gt, tgt)
        return self.register(pi_s, mu_s, mu_t, s_t), self.register(pi_t, mu_t, mu_s, s_s), gs, pi_t

    def loss(self, T, T21, T_gt):
        if self.cfg["loss"] == "transform":
            eye = torch.eye(4).expand_as(T)
            a = ((T @ torch.inverse(T_gt) - eye) ** 2).mean()
            b = ((T21 @ T_gt - eye) ** 2).mean()
            return {"T12": a, "T21": b, "total": a + b}
        R, t = T[:, :3, :3], T[:, :3, 3]
        rot = ((R.transpose(1, 2) @ T_gt[:, :3, :3] - torch.eye(3)) ** 2).mean()
        tra = ((t - T_gt[:, :3, 3]) ** 2).mean()
        return {"rotation": rot, "translation": tra, "total": rot + tra}


def formula_motion(batch):
    """T_gt of pair b: rotation 0.3 + 0.2 b rad about the axis (1, 2, 2)/3, t = (0.1, -0.2, 0.05 b)."""
    out = torch.eye(4).repeat(batch, 1, 1)
    for b in range(batch):
        axis = torch.tensor([1.0, 2.0, 2.0], dtype=torch.float64) / 3
        a = 0.3 + 0.2 * b
        K = torch.tensor([[0, -axis[2], axis[1]], [axis[2], 0, -axis[0]], [-axis[1], axis[0], 0]],
                         dtype=torch.float64)
        R = torch.eye(3, dtype=torch.float64) + math.sin(a) * K + (1 - math.cos(a)) * K @ K
        out[b, :3, :3] = R.float()
        out[b, :3, 3] = torch.tensor([0.1, -0.2, 0.05 * b])
    return out


def deepgmr_run(cfg, n, m, train, dtype):
    torch.set_default_dtype(dtype)
    try:
        net = DeepGmr(cfg)
        formula_fill(net)
        net.train(train)
        src, tgt = formula_cloud(2, n, 0.0).to(dtype), formula_cloud(2, m, 1.0).to(dtype)
        with torch.no_grad():
            T, T21, gs, pi_t = net(src, tgt)
            return T, T21, gs, pi_t, net.loss(T, T21, formula_motion(2).to(dtype))
    finally:
        torch.set_default_dtype(torch.float32)


def deepgmr_case(cfg, n, m, train):
    """float32 outputs, plus how far float32 rounding moves T (max |T32 - T64| over T, T21):
    the scale for the C++ test's tolerance."""
    T, T21, gs, pi_t, terms = deepgmr_run(cfg, n, m, train, torch.float32)
    T64, T21_64 = deepgmr_run(cfg, n, m, train, torch.float64)[:2]
    gap = max((T.double() - T64).abs().max(), (T21.double() - T21_64).abs().max())
    return {"T": as_list(T), "T21": as_list(T21), "gamma_source_sq_sum": float((gs * gs).sum()),
            "pi_target_sq_sum": float((pi_t * pi_t).sum()),
            "loss": {k: float(v) for k, v in terms.items()}, "float64_gap_T": float(gap)}


# ----------------------------------------------------------------------------- fixtures


def phase(name):
    return 0.01 * (sum((k + 1) * ord(ch) for k, ch in enumerate(name)) % 997)


def formula_fill(module):
    """Sets every parameter and BN buffer from the formula in the module docstring."""
    with torch.no_grad():
        for name, t in list(module.named_parameters()) + list(module.named_buffers()):
            if name.endswith("num_batches_tracked"):
                continue
            i = torch.arange(t.numel(), dtype=torch.float64)
            s = torch.sin(0.37 * i + 0.0013 * i * i + phase(name))
            if name.endswith("running_mean"):
                v = 0.1 * s
            elif name.endswith("running_var"):
                v = 1 + 0.5 * s * s
            elif t.dim() >= 2:
                v = s / math.sqrt(t.numel() / t.shape[0])
            elif name.endswith("weight"):
                v = 1 + 0.1 * s
            else:
                v = 0.1 * s
            t.copy_(v.view(t.shape).to(t.dtype))


def formula_cloud(batch, n, seed):
    i = torch.arange(n, dtype=torch.float64)
    out = []
    for b in range(batch):
        s = seed + b
        out.append(torch.stack([0.5 * torch.sin(0.9 * i + s), 0.5 * torch.cos(1.7 * i + 2 * s),
                                0.5 * torch.sin(0.23 * i + 0.013 * i * i + 3 * s)], 1))
    return torch.stack(out).float()


def as_list(t):
    return [round(float(v), 7) for v in t.reshape(-1).tolist()]


def small_config(**over):
    cfg = dict(emb_dims=32, anchors=8, clusters=8, heads=4, k=10, spe_k=5, spe=True, csa=True,
               attention="clustered", osp=True, fix_overlap_index=False, gmm_iterations=10,
               sinkhorn_epsilon=0.01, sinkhorn_threshold=0.01, sinkhorn_iterations=10,
               match_temperature=0.05, w_pose=10.0, w_clu=1.0, w_ovl=1.0, w_welsch=0.01,
               nt_xent_temperature=0.1, welsch_alpha=10.0, welsch_keypoints=512)
    cfg.update(over)
    return cfg


def labels_for(batch, n):
    """0/1 labels: point i overlaps when sin(0.5 i + b) > -0.2."""
    i = torch.arange(n, dtype=torch.float64)
    return torch.stack([(torch.sin(0.5 * i + b) > -0.2).float() for b in range(batch)])


def ogmm_case(cfg, n, m, train):
    torch.manual_seed(0)
    net = Ogmm(cfg)
    formula_fill(net)
    net.train(train)
    src, tgt = formula_cloud(2, n, 0.0), formula_cloud(2, m, 1.0)
    T_gt = torch.eye(4).repeat(2, 1, 1)
    T_gt[:, 0, 3] = 0.1
    torch.manual_seed(7)  # FPS starts
    T, aux = net(src, tgt)
    terms = net.loss(src, tgt, T_gt, labels_for(2, n), labels_for(2, m), T, aux)
    return {"T": as_list(T), "overlap_source_sum": float(aux["op"].sum()),
            "overlap_target_sum": float(aux["oq"].sum()),
            "mu_source_sum": float(aux["mu_p"].sum()),
            "loss": {k: float(v) for k, v in terms.items()}}


def main():
    torch.set_num_threads(1)
    out = {}
    # DGCNN (authors' widths, emb 64, k 20) on a 2 x 40-point cloud, eval mode.
    dg = Dgcnn(64, 20)
    formula_fill(dg)
    dg.eval()
    x = formula_cloud(2, 40, 0.0).transpose(1, 2).contiguous()
    with torch.no_grad():
        y = dg(x)
        out["dgcnn"] = {"sum": float(y.sum()), "sq_sum": float((y * y).sum()),
                        "first": as_list(y[0, :4, :3]), "last": as_list(y[1, -3:, -2:])}
        dg.train()
        y = dg(x)
        out["dgcnn_train"] = {"sum": float(y.sum()), "sq_sum": float((y * y).sum())}
        # Attention (d 32, 4 heads): 2 x 32 x 20 queries onto 2 x 32 x 7 keys from the formula.
        att = Attention(32, 4)
        formula_fill(att)
        xs = torch.sin(0.05 * torch.arange(2 * 32 * 20, dtype=torch.float64)).view(2, 32, 20).float()
        ks = torch.cos(0.11 * torch.arange(2 * 32 * 7, dtype=torch.float64)).view(2, 32, 7).float()
        y = att(xs, ks)
        out["attention"] = {"sum": float(y.sum()), "sq_sum": float((y * y).sum()),
                            "first": as_list(y[0, :4, :3])}
        spe = Spe(32, 5)
        formula_fill(spe)
        spe.eval()
        y = spe(x)
        out["spe"] = {"sum": float(y.sum()), "sq_sum": float((y * y).sum())}
    # Whole network + loss, small config: eval N = M (the code's overlap index), train N != M.
    out["ogmm_eval_equal"] = ogmm_case(small_config(), 64, 64, False)
    out["ogmm_train_unequal"] = ogmm_case(small_config(), 60, 52, True)
    out["ogmm_full_fixed_nospe"] = ogmm_case(
        small_config(attention="full", fix_overlap_index=True, spe=False), 48, 48, False)
    # DeepGMR, batch 2, N != M: the paper's variant (small widths) in train and eval mode, the
    # original on centred xyz and on RRI (k 6), train mode. Train mode (BatchNorm on batch
    # statistics) gives peaked assignments and well-separated mixture means; with the formula's
    # running statistics eval mode gives nearly uniform gamma (kept for the eval path).
    dg_cfg = dict(features="dgcnn", clusters=8, emb_dims=32, dgcnn_k=10, head_hidden=16,
                  rri_k=20, loss="pose")
    out["deepgmr_dgcnn_train"] = deepgmr_case(dg_cfg, 48, 40, True)
    out["deepgmr_dgcnn_eval"] = deepgmr_case(dg_cfg, 48, 40, False)
    out["deepgmr_xyz_train"] = deepgmr_case(dict(dg_cfg, features="xyz", clusters=16,
                                                 loss="transform"), 40, 36, True)
    out["deepgmr_rri_train"] = deepgmr_case(dict(dg_cfg, features="rri", clusters=16, rri_k=6,
                                                 loss="transform"), 40, 36, True)
    print(json.dumps(out, indent=1))


if __name__ == "__main__":
    main()
