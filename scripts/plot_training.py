#!/usr/bin/python3
"""Plots a training run's curves from its metrics.csv into a PNG (Debian's python3-matplotlib).

Usage: scripts/plot_training.py RUN/metrics.csv OUT.png [TITLE]
Left: train and validation loss; middle: validation MAE(R) of the network alone and after ICP,
with the identity's MAE(R) on the same pairs as the floor; right: validation CCD (network alone,
after ICP) and recall (fraction of validation pairs under 1 deg and 0.1 units, after ICP) on a
second axis. x axis: training steps.
"""
import csv
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

rows = list(csv.DictReader(open(sys.argv[1])))
step = [int(r["step"]) for r in rows]
col = lambda k: [float(r[k]) for r in rows]  # noqa: E731
fig, (a, b, c) = plt.subplots(1, 3, figsize=(15, 3.6))
a.plot(step, col("train_loss"), "o-", label="train loss (epoch mean)")
a.plot(step, col("val_loss"), "s--", label="validation loss")
a.set_xlabel("step")
a.legend()
b.plot(step, col("mae_r"), "o-", label="network alone")
b.plot(step, col("mae_r_icp"), "s--", label="+ ICP")
b.plot(step, col("identity_mae_r"), ":", color="grey", label="identity")
b.set_xlabel("step")
b.set_ylabel("validation MAE(R) [deg]")
b.legend()
c.plot(step, col("ccd"), "o-", label="CCD, network alone")
c.plot(step, col("ccd_icp"), "s--", label="CCD, + ICP")
c.set_xlabel("step")
c.set_ylabel("validation CCD")
r = c.twinx()
r.plot(step, col("recall_icp"), "^:", color="tab:green", label="recall, + ICP")
r.set_ylabel("recall")
lines = c.get_legend_handles_labels()[0] + r.get_legend_handles_labels()[0]
c.legend(lines, [ln.get_label() for ln in lines], fontsize="small")
if len(sys.argv) > 3:
    fig.suptitle(sys.argv[3])
fig.tight_layout()
fig.savefig(sys.argv[2], dpi=90)
