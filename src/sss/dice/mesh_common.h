#pragma once
// Internal helpers shared by the polygon and subdivision-mesh dicers
// (dice_mesh.cpp, subdivision.cpp): validation errors, positions and
// per-corner primitive variables.

#include <cstddef>
#include <string>
#include <string_view>
#include <vector>

#include <glm/vec3.hpp>

#include "sss/scene/scene.h"

namespace sss::detail {

/// Throws ValueError "<source>: <Kind>: <what>".
[[noreturn]] void throw_mesh_error(const Primitive& prim, const std::string& what);

/// The object-space positions of "P" (or "Pw", divided by w). ValueError when
/// both are missing, the number count is not a whole number of points, or a
/// coordinate is not finite.
std::vector<glm::dvec3> read_positions(const Primitive& prim);

/// A 3-component primitive variable ("Cs", "N") looked up per face corner
/// through its storage class: constant (one value), uniform (per face),
/// varying/vertex (per point, by vertex index) or facevarying/facevertex (per
/// face corner, in face order).
class CornerVec3 {
public:
    /// Absent variable: present() is false. ValueError when it is given with
    /// the wrong type or fewer values than its class needs for this primitive
    /// (`faces` uniform values, `points` vertex values, `corners` facevarying).
    CornerVec3(const Primitive& prim, std::string_view name, std::size_t faces,
               std::size_t points, std::size_t corners);

    bool present() const { return m_data != nullptr; }
    /// Value at corner `corner` (running corner number) of face `face`, whose
    /// point index is `point`.
    glm::dvec3 at(std::size_t face, std::size_t point, std::size_t corner) const {
        std::size_t i = 0;
        switch (m_class) {
        case ParamClass::Constant:
            i = 0;
            break;
        case ParamClass::Uniform:
            i = face;
            break;
        case ParamClass::Varying:
        case ParamClass::Vertex:
            i = point;
            break;
        case ParamClass::FaceVarying:
        case ParamClass::FaceVertex:
            i = corner;
            break;
        }
        const double* v = m_data + 3 * i;
        return {v[0], v[1], v[2]};
    }

private:
    const double* m_data = nullptr;
    ParamClass m_class = ParamClass::Constant;
};

} // namespace sss::detail
