#!/usr/bin/env python3
# Copyright The sss Authors
# SPDX-License-Identifier: Apache-2.0
"""Writes blob.obj: a lumpy closed mesh (a UV sphere with low-frequency bumps),
quads with triangle caps, outward counter-clockwise faces and vertex normals."""
import math

NU, NV = 64, 32  # segments around, rings pole to pole


def radius(theta, phi):
    return 1.0 + 0.18 * math.sin(3 * theta) * math.sin(phi) ** 2 + 0.1 * math.cos(2 * phi)


def point(theta, phi):
    r = radius(theta, phi)
    return (r * math.sin(phi) * math.cos(theta), r * math.cos(phi), r * math.sin(phi) * math.sin(theta))


verts = [point(0.0, 0.0)]
for j in range(1, NV):
    phi = math.pi * j / NV
    for i in range(NU):
        verts.append(point(2 * math.pi * i / NU, phi))
verts.append(point(0.0, math.pi))
south = len(verts)  # 1-based index of the last vertex


def ring(j, i):  # 1-based OBJ index of ring j (1..NV-1), segment i
    return 2 + (j - 1) * NU + (i % NU)


faces = []
for i in range(NU):
    faces.append((1, ring(1, i + 1), ring(1, i)))
for j in range(1, NV - 1):
    for i in range(NU):
        faces.append((ring(j, i), ring(j, i + 1), ring(j + 1, i + 1), ring(j + 1, i)))
for i in range(NU):
    faces.append((south, ring(NV - 1, i), ring(NV - 1, i + 1)))

# Make every face counter-clockwise seen from outside: check against the centre.
def sub(a, b):
    return (a[0] - b[0], a[1] - b[1], a[2] - b[2])


def cross(a, b):
    return (a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0])


fixed = []
normals = [[0.0, 0.0, 0.0] for _ in verts]
for f in faces:
    p = [verts[k - 1] for k in f]
    n = cross(sub(p[1], p[0]), sub(p[2], p[0]))
    c = [sum(q[a] for q in p) / len(p) for a in range(3)]
    if n[0] * c[0] + n[1] * c[1] + n[2] * c[2] < 0:
        f = tuple(reversed(f))
        n = (-n[0], -n[1], -n[2])
    fixed.append(f)
    for k in f:
        for a in range(3):
            normals[k - 1][a] += n[a]

with open("blob.obj", "w") as out:
    out.write("# lumpy blob for the varying-albedo bake (scenes/varying/make_blob.py)\n")
    for v in verts:
        out.write("v %.6f %.6f %.6f\n" % v)
    for n in normals:
        l = math.sqrt(sum(x * x for x in n))
        out.write("vn %.6f %.6f %.6f\n" % tuple(x / l for x in n))
    for f in fixed:
        out.write("f " + " ".join("%d//%d" % (k, k) for k in f) + "\n")
