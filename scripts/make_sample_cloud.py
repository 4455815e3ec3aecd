#!/usr/bin/env python3
# SPDX-License-Identifier: GPL-3.0-or-later
"""Writes examples/data/sample.xyz: 20,000 points on a (2,3) torus-knot tube
(a closed surface whose strands pass close to each other), with exact
normals given random signs and a small angular perturbation, the input
orient_normals expects.  Deterministic: python3 scripts/make_sample_cloud.py"""
import math, random

def knot(t):
    # (2,3) torus knot on a torus of radii 2 and 1
    r = 2.0 + math.cos(3 * t)
    return (r * math.cos(2 * t), r * math.sin(2 * t), -math.sin(3 * t))

def sub(a, b): return (a[0] - b[0], a[1] - b[1], a[2] - b[2])
def cross(a, b): return (a[1]*b[2]-a[2]*b[1], a[2]*b[0]-a[0]*b[2], a[0]*b[1]-a[1]*b[0])
def norm(a):
    l = math.sqrt(a[0]**2 + a[1]**2 + a[2]**2)
    return (a[0]/l, a[1]/l, a[2]/l)

def main():
    rng = random.Random(20261121)
    tube = 0.35
    steps = 4000
    # arc-length weights so that sampling is area-uniform along the curve
    ts = [2 * math.pi * i / steps for i in range(steps + 1)]
    lengths = [math.dist(knot(ts[i]), knot(ts[i + 1])) for i in range(steps)]
    total = sum(lengths)
    cumulative, acc = [], 0.0
    for l in lengths:
        acc += l
        cumulative.append(acc / total)
    with open("examples/data/sample.xyz", "w") as out:
        for _ in range(20000):
            u = rng.random()
            lo, hi = 0, steps - 1
            while lo < hi:
                mid = (lo + hi) // 2
                if cumulative[mid] < u: lo = mid + 1
                else: hi = mid
            t = ts[lo] + rng.random() * (ts[1] - ts[0])
            c = knot(t)
            tangent = norm(sub(knot(t + 1e-4), knot(t - 1e-4)))
            helper = (0.0, 0.0, 1.0) if abs(tangent[2]) < 0.9 else (1.0, 0.0, 0.0)
            b1 = norm(cross(tangent, helper))
            b2 = cross(tangent, b1)
            a = rng.random() * 2 * math.pi
            n = tuple(math.cos(a) * b1[i] + math.sin(a) * b2[i] for i in range(3))
            p = tuple(c[i] + tube * n[i] for i in range(3))
            # unoriented normal: small angular noise, random sign
            noisy = norm(tuple(n[i] + rng.gauss(0, 0.05) for i in range(3)))
            s = 1 if rng.random() < 0.5 else -1
            out.write("%.6f %.6f %.6f %.5f %.5f %.5f\n" % (p + tuple(s * x for x in noisy)))

if __name__ == "__main__":
    main()
