#!/usr/bin/env python3
# Copyright The sss Authors
# SPDX-License-Identifier: Apache-2.0
"""Writes ear.obj: an ear-like closed shell for the skin scene (scenes/skin), in cm.

A cupped, leaf-shaped lobe about 4 x 6 cm in the xy plane, y up, its hollow side facing
-z (the camera). It is thick in the middle (1.4 cm) and thin at the rim (about 2 mm),
with a ridge (an "antihelix") in between, so that light from behind bleeds red through
the thin parts. Quads with triangle fans at the two poles (the middle of the front and
the back), faces anticlockwise seen from outside, vertex normals.

usage: python3 make_ear.py [out.obj]      (default: ear.obj next to this script)
"""
import math
import os
import sys

NU, NV = 96, 48  # segments around the outline, rings from the front pole to the back one


def outline(theta):
    """Half-widths of the outline at angle theta: a rounded top, a narrower lobe below."""
    s = math.sin(theta)
    ax = 1.9 * (1.0 - 0.22 * max(0.0, -s) ** 2) * (1.0 + 0.06 * math.cos(3 * theta))
    by = 3.0 * (1.0 + 0.05 * s)
    return ax, by


def half_thickness(s, theta):
    """Half the thickness at radial fraction s (0 middle, 1 rim)."""
    h = 0.10 + 0.6 * (1.0 - s * s) ** 1.5
    h += 0.16 * math.exp(-(((s - 0.62) / 0.09) ** 2)) * (0.6 + 0.4 * math.sin(theta))
    return h


def point(theta, phi):
    s = math.sin(phi)
    c = math.cos(phi)
    ax, by = outline(theta)
    x = ax * s * math.cos(theta)
    y = by * s * math.sin(theta) + 0.3
    # Blunt superellipse profile (|cos|^0.6): a rounded rim instead of a knife edge.
    z = -math.copysign(abs(c) ** 0.6, c) * half_thickness(s, theta)
    # Cupped towards the camera (the rim comes forward), more at the top, with a twist.
    z -= (0.9 + 0.3 * math.sin(theta)) * s ** 3 + 0.15 * x * y / 3.0
    return (x, y, z)


def main():
    out_path = sys.argv[1] if len(sys.argv) > 1 else os.path.join(
        os.path.dirname(os.path.abspath(__file__)), "ear.obj")
    verts = [point(0.0, 0.0)]  # front pole
    for j in range(1, NV):
        phi = math.pi * j / NV
        for i in range(NU):
            verts.append(point(2 * math.pi * i / NU, phi))
    verts.append(point(0.0, math.pi))  # back pole
    back = len(verts)  # 1-based index of the back pole

    def ring(j, i):  # 1-based OBJ index of ring j (1..NV-1), segment i
        return 2 + (j - 1) * NU + (i % NU)

    # One consistent winding over the whole (sphere-like) parameter grid.
    faces = [(1, ring(1, i), ring(1, i + 1)) for i in range(NU)]
    for j in range(1, NV - 1):
        for i in range(NU):
            faces.append((ring(j, i), ring(j + 1, i), ring(j + 1, i + 1), ring(j, i + 1)))
    faces += [(back, ring(NV - 1, i + 1), ring(NV - 1, i)) for i in range(NU)]

    def sub(a, b):
        return (a[0] - b[0], a[1] - b[1], a[2] - b[2])

    def cross(a, b):
        return (a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0])

    def face_normal(f):  # Newell's method: area-weighted
        n = [0.0, 0.0, 0.0]
        for k in range(len(f)):
            p, q = verts[f[k] - 1], verts[f[(k + 1) % len(f)] - 1]
            n[0] += (p[1] - q[1]) * (p[2] + q[2])
            n[1] += (p[2] - q[2]) * (p[0] + q[0])
            n[2] += (p[0] - q[0]) * (p[1] + q[1])
        return n

    # Outward at the front pole is -z (towards the camera): flip everything if not.
    if face_normal(faces[0])[2] > 0:
        faces = [tuple(reversed(f)) for f in faces]

    normals = [[0.0, 0.0, 0.0] for _ in verts]
    for f in faces:
        n = face_normal(f)
        for k in f:
            for a in range(3):
                normals[k - 1][a] += n[a]

    with open(out_path, "w") as out:
        out.write("# ear-like shell for the skin scene (scenes/skin/make_ear.py), cm\n")
        for v in verts:
            out.write("v %.4f %.4f %.4f\n" % v)
        for n in normals:
            length = math.sqrt(sum(x * x for x in n)) or 1.0
            out.write("vn %.4f %.4f %.4f\n" % tuple(x / length for x in n))
        for f in faces:
            out.write("f " + " ".join("%d//%d" % (k, k) for k in f) + "\n")


if __name__ == "__main__":
    main()
