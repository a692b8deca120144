#!/usr/bin/env python3
"""Writes a measured BRDF table in MERL's .binary layout, made from a known function, to try the
service's measured BRDFs without a real MERL file (docs/api.md, Measured BRDFs).

    python3 examples/make_merl.py lambert white.binary            # albedo 1
    python3 examples/make_merl.py ggx ggx.binary --roughness 0.3  # GGX as shaders/brdfs/ggx.brdf

Each bin holds the function at the bin's centre: theta_h = ((i + 1/2) / 90)^2 pi/2, theta_d and
phi_d at the centres of their linear bins. GGX bins with a direction below the horizon hold no
data (-1), as a gonioreflectometer measures none there. Standard library only.
"""
import argparse
import array
import math
import struct
import sys

TH, TD, PD = 90, 90, 180
SCALE = (1.0 / 1500.0, 1.15 / 1500.0, 1.66 / 1500.0)


def directions(h, d, p):
    """L and V (unit, normal +z) at the centre of bin (h, d, p), with phi_h = 0."""
    th = ((h + 0.5) / TH) ** 2 * math.pi / 2
    td = (d + 0.5) / TD * math.pi / 2
    pd = (p + 0.5) / PD * math.pi
    dx, dy, dz = math.sin(td) * math.cos(pd), math.sin(td) * math.sin(pd), math.cos(td)
    # L: the difference vector turned by theta_h about +y; V: L mirrored about the half vector.
    lx, ly, lz = math.cos(th) * dx + math.sin(th) * dz, dy, -math.sin(th) * dx + math.cos(th) * dz
    hx, hz = math.sin(th), math.cos(th)
    hl = hx * lx + hz * lz
    return (lx, ly, lz), (2 * hl * hx - lx, -ly, 2 * hl * hz - lz)


def ggx(L, V, alpha, f0):
    """D_GGX * V_SmithGGXCorrelated * F_Schlick(V.H), as shaders/brdfs/ggx.brdf computes it."""
    nl, nv = L[2], V[2]
    hx, hy, hz = L[0] + V[0], L[1] + V[1], L[2] + V[2]
    n = math.sqrt(hx * hx + hy * hy + hz * hz)
    nh, vh = hz / n, (V[0] * hx + V[1] * hy + V[2] * hz) / n
    a2 = alpha * alpha
    dd = nh * nh * (a2 - 1) + 1
    D = a2 / (math.pi * dd * dd)
    vis = 0.5 / (nl * math.sqrt(nv * nv * (1 - a2) + a2) + nv * math.sqrt(nl * nl * (1 - a2) + a2))
    s = min(max(1 - vh, 0.0), 1.0) ** 5
    return [D * vis * (f + (1 - f) * s) for f in f0]


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("model", choices=["lambert", "ggx"])
    ap.add_argument("output")
    ap.add_argument("--albedo", type=float, nargs=3, default=[1, 1, 1], help="lambert: rho per channel")
    ap.add_argument("--roughness", type=float, default=0.3, help="ggx: alpha")
    ap.add_argument("--f0", type=float, nargs=3, default=[0.95, 0.64, 0.54], help="ggx: F0 per channel")
    args = ap.parse_args()
    bins = TH * TD * PD
    planes = [array.array("d", bytes(8 * bins)) for _ in range(3)]
    for h in range(TH):
        for d in range(TD):
            for p in range(PD):
                i = p + PD * d + PD * TD * h
                if args.model == "lambert":
                    f = [a / math.pi for a in args.albedo]
                else:
                    L, V = directions(h, d, p)
                    f = None if L[2] <= 0 or V[2] <= 0 else ggx(L, V, args.roughness, args.f0)
                for c in range(3):
                    planes[c][i] = -1.0 if f is None else f[c] / SCALE[c]
    if sys.byteorder != "little":
        for plane in planes:
            plane.byteswap()
    with open(args.output, "wb") as out:
        out.write(struct.pack("<3i", TH, TD, PD))
        for plane in planes:
            out.write(plane.tobytes())


if __name__ == "__main__":
    main()
