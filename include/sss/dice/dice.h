// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
#pragma once
/// \file dice.h
/// The dice module owns dicing: primitives of the scene layer become
/// micropolygons and ray-tracing triangles, one primitive or many in
/// parallel.
/// May use: scene and util.
///
/// Dicing: every primitive of the scene layer becomes micropolygons (one
/// point each, with its exact area, normal and radius) and triangles for the
/// ray tracer. View-independent: nothing is culled, and micropolygon size is
/// either a fixed world length or ShadingRate raster pixels of the scene's
/// camera measured at the surface's distance from the eye, ignoring its
/// orientation (REYES with raster-oriented dicing off).

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <memory>
#include <span>
#include <string>
#include <vector>

#include <glm/vec3.hpp>
#include <glm/vec4.hpp>

#include "sss/scene/scene.h"
#include "sss/util/limits.h"

namespace sss {

/// A grid of points handed to DiceControl::displace, in world space: a
/// diced grid's vertices or its micropolygon centres (nu x nv points, u
/// fastest), or unrelated points (`grid` false: vertices the dicer adds
/// between grids, whose neighbours are not known).
struct DisplaceGrid {
    const Primitive* primitive = nullptr;
    bool grid = true;
    int nu = 0, nv = 0;    ///< grid: size() == nu * nv; points: nu == size(), nv == 1
    uint64_t sequence = 0; ///< running number of the call for this primitive (seeds)
    // In: the undisplaced surface. The hook writes the displaced P and N.
    std::vector<glm::vec3> P;
    std::vector<glm::vec3> N;  ///< unit shading normal (orientation applied)
    std::vector<glm::vec3> Ng; ///< unit geometric normal (orientation applied)
    // In only, per point: parametric coordinates of the primitive, the
    // grid's parameter steps, the undisplaced tangents and the texture
    // coordinates.
    std::vector<float> u, v, du, dv, s, t;
    std::vector<glm::vec3> dPdu, dPdv;

    std::size_t size() const { return P.size(); }
    /// Sizes every array for n points.
    void resize(std::size_t n) {
        for (auto* a : {&P, &N, &Ng, &dPdu, &dPdv}) a->resize(n);
        for (auto* a : {&u, &v, &du, &dv, &s, &t}) a->resize(n);
    }
};

/// Moves the points of a grid (a displacement shader); see DiceControl::displace.
using DisplaceHook = std::function<void(DisplaceGrid& grid)>;

/// The choices a dicing makes from the geometry (grid sizes, splits, the
/// longest side of a triangle), recorded by one dicing and replayed by
/// another of the same topology, so that both make the same triangles:
/// motion blur dices a moving primitive at each time step with the choices
/// made at the first. One dicing at a time (not thread-safe).
class DiceJournal {
public:
    /// While recording: keeps `value` and returns it. While replaying: the
    /// value recorded at this point (ValueError "<where>: ..." when the
    /// replay asks for more than was recorded).
    double note(double value, const std::string& where) const;
    /// Replays the recording from its start.
    void replay() {
        m_replaying = true;
        m_next = 0;
    }
    /// Whether a replay used every recorded choice.
    bool replayed_all() const { return m_next == m_values.size(); }

private:
    mutable std::vector<double> m_values;
    mutable std::size_t m_next = 0;
    bool m_replaying = false;
};

/// A depth map as the dicer reads it: the surface a Blobby's repelling
/// ground plane (opcode 1003) keeps its blobs off.
struct DepthGrid {
    int width = 0, height = 0;
    /// The map camera's z of the nearest surface per texel, rows top to
    /// bottom; kNoDepth (or more) where there is none.
    std::vector<float> depth;
    /// World to the map camera's space (z away from the eye) and to its
    /// screen (x, y in [-1, 1] after the division by w, y up).
    Matrix4 world_to_camera{1.0};
    Matrix4 world_to_screen{1.0};
    static constexpr float kNoDepth = 1e30f;
};

/// The depth map a Blobby names, read along the texture search path (the
/// renderers' texture library); throws an sss::Error naming it when it
/// cannot be read as one.
using DepthGridSource =
    std::function<std::shared_ptr<const DepthGrid>(const std::string&)>;

/// How fine to dice.
struct DiceControl {
    /// > 0: micropolygon edge length in world units. 0: from ShadingRate and the camera.
    double spacing = 0.0;
    /// Camera for ShadingRate dicing (spacing == 0).
    const Camera* camera = nullptr;
    /// Edge lengths are multiplied by this (>= 1): surfaces that only cast
    /// shadows need their shape, not micropolygon density.
    double coarsening = 1.0;
    /// No primitive is diced into more than this many micropolygons: a
    /// LimitError names the primitive (file:line) and
    /// SSS_LIMIT_PRIMITIVE_MICROPOLYGONS instead. Limit::PrimitiveMicropolygons
    /// by default (docs/limits.md).
    std::size_t max_micropolygons =
        static_cast<std::size_t>(limit(Limit::PrimitiveMicropolygons));
    /// Fill DicedSurface::grids and the per-micropolygon parametric data
    /// (u, v, du, dv, s, t, dPdu, dPdv) for shading grids.
    bool grids = false;
    /// Displacement, when set: called on every diced grid of vertices (the
    /// triangles' vertices, so that ray tracing sees the displaced surface)
    /// and of micropolygon centres, and on the points the dicer adds
    /// between grids. The hook writes new positions and shading normals
    /// (world space); the dicer then recomputes the micropolygons' areas and
    /// radii from the displaced vertices. Called from the dicing thread.
    DisplaceHook displace;
    /// When set: the dicing's geometric choices go through it (DiceJournal).
    std::shared_ptr<DiceJournal> journal;
    /// The depth maps of Blobby ground planes; unset, a ground plane is an
    /// error naming the primitive.
    DepthGridSource depth_maps;

    /// A choice made from the geometry: `value`, or its journal's.
    double note(double value, const Primitive& prim) const {
        return journal ? journal->note(value, prim.source) : value;
    }

    /// Micropolygon edge length wanted at world point p for a primitive with
    /// the given shading rate: `spacing`, or sqrt(shading_rate) pixels of the
    /// camera at p's distance from the eye (never below the near clip); times
    /// `coarsening`.
    double edge_length_at(const glm::dvec3& world_p, double shading_rate) const;
};

/// A grid of micropolygon centres of a DicedSurface: centres first ..
/// first + nu * nv - 1, u fastest (REYES grids: a face or sub-patch diced
/// into nu x nv micropolygons).
struct DicedGrid {
    std::size_t first = 0;
    int nu = 0, nv = 0;
    std::size_t size() const { return static_cast<std::size_t>(nu) * nv; }
};

/// A diced primitive, in world space.
struct DicedSurface {
    // One entry per micropolygon:
    std::vector<glm::vec3> centers; ///< micropolygon centre (on the surface)
    std::vector<glm::vec3> normals; ///< unit normal (orientation rules applied)
    std::vector<float> areas;       ///< exact area; they add up to the surface area
    std::vector<float> radii;       ///< largest centre-to-corner distance
    std::vector<glm::vec3> colors;  ///< Cs per micropolygon; empty = attributes' Color
    // Watertight triangles covering the same surface, for ray tracing:
    std::vector<glm::vec3> vertices;
    std::vector<glm::vec3> vertex_normals; ///< same size as vertices
    std::vector<uint32_t> triangles;       ///< 3 vertex indices per triangle
    // With DiceControl::grids only (else empty):
    /// The grids the centres form, in centre order; centres in no grid
    /// (triangulated polygons, cells of a grid that had to be dropped) are
    /// shaded as unrelated points.
    std::vector<DicedGrid> grids;
    /// Per micropolygon: the primitive's parametric coordinates of the
    /// centre, the parameter steps of its grid, texture coordinates ("st",
    /// "s", "t" when given, else u and v) and the undisplaced world tangents.
    /// Centres the dicer has no parametrisation for have zeros.
    std::vector<float> u, v, du, dv, s, t;
    std::vector<glm::vec3> dPdu, dPdv;
    /// Per triangle vertex (same size as vertices): the primitive's (u, v)
    /// and the texture coordinates (s, t), as the centres have them, so that
    /// a ray hit can interpolate them over its triangle. Vertices the dicer
    /// adds between grids have the values of their parameters. Triangles
    /// (and triangulated polygons) have no (u, v): zeros, and s, t
    /// interpolated from "st" ("s", "t") when given, else zeros too.
    std::vector<glm::vec4> vertex_uvst;
    /// Motion blur (DiceRequest::times): the vertices and their normals at
    /// each time after the first (the surface itself is at the first), over
    /// the same triangles.
    std::vector<std::vector<glm::vec3>> step_vertices, step_normals;

    /// Whether it moves: vertices at more than one time.
    bool moving() const { return !step_vertices.empty(); }
    /// Vertex v, or its normal, at `time` (0..1 over the steps, evenly
    /// spread): linear between the steps, as the ray tracer has it.
    glm::vec3 vertex_at(uint32_t v, float time) const {
        return step_at(vertices, step_vertices, v, time);
    }
    glm::vec3 normal_at(uint32_t v, float time) const {
        return step_at(vertex_normals, step_normals, v, time);
    }
    static glm::vec3 step_at(const std::vector<glm::vec3>& first,
                             const std::vector<std::vector<glm::vec3>>& steps, uint32_t v,
                             float time) {
        if (steps.empty()) return first[v];
        const float f = std::clamp(time, 0.0f, 1.0f) * static_cast<float>(steps.size());
        const std::size_t i = std::min(static_cast<std::size_t>(f), steps.size() - 1);
        const float w = f - static_cast<float>(i);
        const glm::vec3& a = i == 0 ? first[v] : steps[i - 1][v];
        return (1.0f - w) * a + w * steps[i][v];
    }

    std::size_t size() const { return centers.size(); }
    bool has_parametric() const { return !u.empty(); }
    /// Sizes the parametric arrays for every micropolygon and every vertex
    /// (zeros).
    void resize_parametric(std::size_t micropolygons, std::size_t vertex_count) {
        for (auto* a : {&u, &v, &du, &dv, &s, &t}) a->resize(micropolygons);
        dPdu.resize(micropolygons);
        dPdv.resize(micropolygons);
        vertex_uvst.resize(vertex_count);
    }
    /// Sizes every array: `micropolygons` entries (colours only when
    /// with_colors), `vertices` vertices and `triangles` triangles.
    void resize(std::size_t micropolygons, std::size_t vertex_count,
                std::size_t triangle_count, bool with_colors) {
        centers.resize(micropolygons);
        normals.resize(micropolygons);
        areas.resize(micropolygons);
        radii.resize(micropolygons);
        colors.resize(with_colors ? micropolygons : 0);
        vertices.resize(vertex_count);
        vertex_normals.resize(vertex_count);
        triangles.resize(3 * triangle_count);
    }
};

/// Dices one primitive. Throws ValueError (naming prim.source) on malformed
/// geometry: wrong "P" count, out-of-range indices, degenerate parameters,
/// and a surface with a world-space point that is not finite or lies beyond
/// kMaxWorldCoordinate (docs/scene.md, "Coordinate range"); LimitError when
/// it would make more than control.max_micropolygons micropolygons.
DicedSurface dice_primitive(const Primitive& prim, const DiceControl& control);

/// One primitive for dice_all, and how fine to dice it.
struct DiceRequest {
    std::size_t primitive = 0; ///< index into scene.primitives
    DiceControl control;       ///< its camera (if any) must outlive dice_all
    /// Motion blur: the times to dice a moving primitive at (primitive_at),
    /// the first one with its own choices, the others with the same ones
    /// (DicedSurface::step_vertices). Empty: the primitive as it is.
    std::vector<double> times;
};

/// Dices a moving primitive at each of `times` (at least one) into one
/// surface: the first time's, with the vertices at the other times in
/// step_vertices. ValueError naming the primitive when a time step dices
/// into other triangles (a deformation that changes its triangulation).
DicedSurface dice_moving(const Primitive& prim, const DiceControl& control,
                         const std::vector<double>& times);

/// What dicing makes of a primitive, estimated before anything is diced.
struct DiceEstimate {
    double micropolygons = 0.0;
    double vertices = 0.0;  ///< triangle vertices (DicedSurface::vertices)
    double triangles = 0.0; ///< ray-tracing triangles
    DiceEstimate& operator+=(const DiceEstimate& o) {
        micropolygons += o.micropolygons;
        vertices += o.vertices;
        triangles += o.triangles;
        return *this;
    }
    /// Bytes of the DicedSurface: per micropolygon 32 (centre, normal, area,
    /// radius), 12 more with colours, 48 more with grids' parametric data;
    /// per vertex 24 (position, normal), 16 more with grids; per triangle 12.
    double surface_bytes(bool colors, bool grids) const {
        return micropolygons * (32.0 + (colors ? 12.0 : 0.0) + (grids ? 48.0 : 0.0)) +
               vertices * (24.0 + (grids ? 16.0 : 0.0)) + triangles * 12.0;
    }
};

/// Estimates what dice_primitive(prim, control) makes, from the primitive's
/// world-space area and perimeter and the dicing rate over it (control
/// points of polygons and subdivision cages, a 9 x 9 grid of samples of each
/// parametric face), without allocating per micropolygon: within a factor of
/// about two of the real counts, rather over than under. Displacement is
/// not foreseen. Checks what dice_primitive checks first (ValueError on
/// malformed geometry, and on points that are not finite or lie beyond
/// kMaxWorldCoordinate); LimitError when the estimate exceeds
/// control.max_micropolygons.
DiceEstimate estimate_primitive(const Primitive& prim, const DiceControl& control);

/// Estimates every request (estimate_primitive, in parallel), in request
/// order; throws the first failure in request order (the same for any
/// thread count), then a LimitError "<where>: N micropolygons in the scene
/// exceeds ..." when their sum exceeds Limit::SceneMicropolygons. `where`
/// names the scene (its file).
std::vector<DiceEstimate> estimate_dicing(const Scene& scene,
                                          std::span<const DiceRequest> requests,
                                          const std::string& where);

/// Per-surface work that belongs with the dicing: called by dice_all with
/// the primitive's index and its surface, right after it is diced, in the
/// same task.
using DiceFinish = std::function<void(std::size_t primitive, DicedSurface& surface)>;

/// Dices the requested primitives of `scene` in parallel (TBB) and returns
/// one surface per primitive of the scene, by index: the requested ones
/// diced (then passed to `finish`, when given), every other one empty.
/// Every request is tried; then, if any failed (in dice_primitive or in
/// `finish`), rethrows the first failure in request order (its own type:
/// ValueError, LimitError, std::bad_alloc...), so that the error and the
/// surfaces are the same for any number of threads. Requests name distinct
/// primitives.
std::vector<DicedSurface> dice_all(const Scene& scene,
                                   std::span<const DiceRequest> requests,
                                   const DiceFinish& finish = {});

/// For surfaces with per-micropolygon colours: each triangle's colour, the
/// colour of the micropolygon centre nearest to its centroid (of equally
/// near ones the lowest index), found in a k-d tree of the centres: O(n log
/// n) whatever the sizes of the micropolygons. Empty without colours.
std::vector<glm::vec3> triangle_colors(const DicedSurface& d);

/// Surface area of a quadric primitive in its object space, computed
/// independently of the dicer (closed forms, or an accurate 1D quadrature of
/// the surface of revolution): for tests and checks. ValueError for other kinds.
double quadric_area(const Primitive& prim);

} // namespace sss
