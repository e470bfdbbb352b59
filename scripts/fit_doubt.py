#!/usr/bin/env python3
"""Calibrates the tracker's doubt (issue 90): a logistic model of "more than 0.2 torso off" from
the features `videomocap-bench learned --split dev --doubt-dump FILE` writes, fitted by
iteratively reweighted least squares (a small ridge keeps it finite). Prints the weights for
`track::doubt::WEIGHTS`, the calibration per probability decile, and recall / precision at each
threshold (dev only: the threshold is chosen here, test reads it once)."""
import csv
import sys

import numpy as np


def main(path):
    with open(path) as f:
        rows = list(csv.reader(f))
    head, rows = rows[0], rows[1:]
    names = head[3:-1]
    x = np.array([[float(v) for v in r[3:-1]] for r in rows])
    y = np.array([float(r[-1]) for r in rows])
    a = np.hstack([x, np.ones((len(x), 1))])
    w = np.zeros(a.shape[1])
    ridge = 1e-3 * np.eye(a.shape[1])
    ridge[-1, -1] = 0.0
    for _ in range(50):
        p = 1.0 / (1.0 + np.exp(-(a @ w)))
        g = a.T @ (p - y) + ridge @ w * len(y)
        h = (a * (p * (1 - p))[:, None]).T @ a + ridge * len(y)
        step = np.linalg.solve(h, g)
        w -= step
        if np.abs(step).max() < 1e-8:
            break
    p = 1.0 / (1.0 + np.exp(-(a @ w)))
    print(f"{len(y)} joint-frames, {int(y.sum())} off ({y.mean():.3f})")
    print("weights:", ", ".join(f"{n} {v:.3f}" for n, v in zip(names + ["intercept"], w)))
    print("const WEIGHTS: [f64; FEATURE_COUNT + 1] = [" + ", ".join(f"{v:.3f}" for v in w) + "];")
    print("calibration (predicted → observed):")
    for lo in np.arange(0, 1, 0.1):
        m = (p >= lo) & (p < lo + 0.1)
        if m.sum():
            print(f"  {lo:.1f}–{lo + 0.1:.1f}: {m.sum():6d} predicted {p[m].mean():.3f} observed {y[m].mean():.3f}")
    print("threshold recall precision shown")
    for t in [0.1, 0.15, 0.2, 0.25, 0.3, 0.35, 0.4, 0.5, 0.55, 0.6]:
        shown = p > t
        both = (shown & (y > 0.5)).sum()
        print(f"  {t:.2f} {both / max(y.sum(), 1):.3f} {both / max(shown.sum(), 1):.3f} {shown.mean():.3f}")


if __name__ == "__main__":
    main(sys.argv[1])
