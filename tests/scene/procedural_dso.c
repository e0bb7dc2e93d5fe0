// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
/* A DynamicLoad procedural for the tests, in C as such DSOs are written:
 * compiled against sss/scene/ri.h alone. The first word of the data string
 * picks what Subdivide makes:
 *   "tree N"        a sphere, then two child procedurals of its own (depth
 *                   N: 2^(N+1)-1 spheres), each with its own data and Free
 *   "mesh"          a shaded PointsPolygons quad with Cs and an inline
 *                   declared variable, cubic Curves with width, a Patch
 *   "archive FILE"  RiProcedural with RiProcDelayedReadArchive of FILE
 *   "load DSO DATA" RiProcedural with RiProcDynamicLoad of another DSO
 *   "undeclared"    a sphere with an undeclared parameter (an error)
 *   "unbalanced"    an AttributeBegin without its end (an error)
 *   "early"         an Ri call in ConvertParameters (an error)
 * sss_test_live_blocks() counts the data blocks not freed yet. */

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <ri.h>

static int live_blocks = 0;

int sss_test_live_blocks(void) { return live_blocks; }

typedef struct {
    char mode[32];
    char arg[1024];
    char arg2[1024];
    int depth;
} Data;

static void* new_block(size_t n) {
    ++live_blocks;
    return calloc(1, n);
}

static void free_block(RtPointer p) {
    --live_blocks;
    free(p);
}

RtPointer ConvertParameters(RtString paramstr) {
    Data* d = (Data*)new_block(sizeof(Data));
    sscanf(paramstr, "%31s %1023s %1023s", d->mode, d->arg, d->arg2);
    d->depth = atoi(d->arg);
    if (strcmp(d->mode, "early") == 0) RiSphere(1.0f, -1.0f, 1.0f, 360.0f, RI_NULL);
    return d;
}

static void tree(RtPointer data, RtFloat detail);

static void tree_level(int depth) {
    RiSphere(0.5f, -0.5f, 0.5f, 360.0f, RI_NULL);
    if (depth <= 0) return;
    for (int side = -1; side <= 1; side += 2) {
        int* child = (int*)new_block(sizeof(int));
        *child = depth - 1;
        RtBound bound = {-1, 1, -1, 1, -1, 1};
        RiTransformBegin();
        RiTranslate(1.5f * side, 0.0f, -1.0f);
        RiScale(0.5f, 0.5f, 0.5f);
        RiProcedural(child, bound, tree, free_block);
        RiTransformEnd();
    }
}

static void tree(RtPointer data, RtFloat detail) {
    (void)detail;
    tree_level(*(int*)data);
}

static void mesh(void) {
    RtInt nverts[1] = {4};
    RtInt verts[4] = {0, 1, 2, 3};
    RtPoint P[4] = {{-1, -1, 0}, {1, -1, 0}, {1, 1, 0}, {-1, 1, 0}};
    RtColor Cs[4] = {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}, {1, 1, 1}};
    RtFloat weight[1] = {0.25f};
    RtFloat kd = 0.8f;
    RtColor white = {1, 1, 1};
    RtToken kfoo = RiDeclare("Kfoo", "varying float");
    RtFloat foo[4] = {0, 1, 2, 3};
    RiAttributeBegin();
    RiColor(white);
    RiSurface("matte", "Kd", &kd, RI_NULL);
    RiPointsPolygons(1, nverts, verts, RI_P, P, RI_CS, Cs, "uniform float weight", weight,
                     kfoo, foo, RI_NULL);
    RiAttributeEnd();

    RtInt nv[2] = {4, 7};
    RtPoint cp[11] = {{0, 0, 0}, {0, 0, 1}, {0, 1, 1}, {0, 1, 2}, {1, 0, 0}, {1, 0, 1},
                      {1, 1, 1}, {1, 1, 2}, {1, 2, 2}, {1, 2, 3}, {1, 3, 3}};
    /* b-spline, step 1: 1 + 4 segments, varying 2 + 5 values */
    RtFloat width[7] = {0.1f, 0.1f, 0.1f, 0.1f, 0.1f, 0.1f, 0.1f};
    RiBasis(RiBSplineBasis, RI_BSPLINESTEP, RiBSplineBasis, RI_BSPLINESTEP);
    RiCurves(RI_CUBIC, 2, nv, RI_NONPERIODIC, RI_P, cp, RI_WIDTH, width, RI_NULL);

    RtPoint quad[4] = {{2, 0, 0}, {3, 0, 0}, {2, 1, 0}, {3, 1, 0}};
    RiPatch(RI_BILINEAR, RI_P, quad, RI_NULL);
}

RtVoid Subdivide(RtPointer data, RtFloat detail) {
    Data* d = (Data*)data;
    (void)detail;
    if (strcmp(d->mode, "tree") == 0) {
        tree_level(d->depth);
    } else if (strcmp(d->mode, "mesh") == 0) {
        mesh();
    } else if (strcmp(d->mode, "archive") == 0) {
        RtString* names = (RtString*)malloc(sizeof(RtString));
        names[0] = d->arg;
        RtBound bound = {-1, 1, -1, 1, -1, 1};
        RiProcedural(names, bound, RiProcDelayedReadArchive, RiProcFree);
    } else if (strcmp(d->mode, "load") == 0) {
        RtString* args = (RtString*)malloc(2 * sizeof(RtString));
        args[0] = d->arg;
        args[1] = d->arg2;
        RtBound bound = {-1, 1, -1, 1, -1, 1};
        RiProcedural(args, bound, RiProcDynamicLoad, RiProcFree);
    } else if (strcmp(d->mode, "undeclared") == 0) {
        RtFloat x = 1.0f;
        RiSphere(1.0f, -1.0f, 1.0f, 360.0f, "notdeclared", &x, RI_NULL);
    } else if (strcmp(d->mode, "unbalanced") == 0) {
        RiAttributeBegin();
        RiSphere(1.0f, -1.0f, 1.0f, 360.0f, RI_NULL);
    }
}

RtVoid Free(RtPointer data) { free_block(data); }
