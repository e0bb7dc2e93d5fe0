// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
#pragma once
/// \file blobby.h
/// The program of a RISpec `Blobby` (implicit surface): its code array
/// decoded into items and checked, so that the RIB reader and the dicer
/// agree on what a program means and on what is wrong with it.
///
/// `Blobby nleaf [code] [floats] [strings]`: every primitive field opcode
/// (1000 constant, 1001 ellipsoid, 1002 segment, 1003 repelling ground
/// plane, 1004 field plugin) and every operator (0 add, 1 multiply, 2 max,
/// 3 min, 4 subtract, 5 divide, 6 negate, 7 identity) makes one item,
/// numbered from 0 in code order; operators name earlier items by number,
/// and the last item is the field. The primitive fields are the leaves,
/// numbered from 0 in code order: the per-leaf primitive variables follow
/// that order. The surface is where the field is kBlobbyThreshold.

#include <array>
#include <cstddef>
#include <string>
#include <vector>

#include <glm/vec3.hpp>

#include "sss/scene/scene.h"
#include "sss/util/error.h"

namespace sss {

/// The field value on the surface (PRMan's): inside where the field is
/// greater.
constexpr double kBlobbyThreshold = 0.5;

/// What an item of a Blobby program does.
enum class BlobbyOp {
    Constant,  ///< 1000: a field of the same value everywhere
    Ellipsoid, ///< 1001: (1 - r^2)^3 in the unit ball a matrix maps onto the ellipsoid
    Segment,   ///< 1002: the same falloff at a distance of up to `radius` from a segment
    GroundPlane, ///< 1003: a repelling ground plane from a depth map
    Plugin,      ///< 1004: an implicit field plugin (not evaluated)
    Add,         ///< 0
    Multiply,    ///< 1
    Max,         ///< 2
    Min,         ///< 3
    Subtract,    ///< 4: operand 0 - operand 1
    Divide,      ///< 5: operand 0 / operand 1 (0 where operand 1 is 0)
    Negate,      ///< 6
    Identity     ///< 7
};

/// The RISpec name of an operation ("ellipsoid", "add"...), for messages.
const char* blobby_op_name(BlobbyOp op);

/// Whether an operation is a primitive field (a leaf).
inline bool blobby_is_leaf(BlobbyOp op) {
    return op == BlobbyOp::Constant || op == BlobbyOp::Ellipsoid ||
           op == BlobbyOp::Segment || op == BlobbyOp::GroundPlane ||
           op == BlobbyOp::Plugin;
}

/// One item of a decoded program.
struct BlobbyItem {
    BlobbyOp op = BlobbyOp::Constant;
    /// The item's opcode and operands are code[code_begin, code_end).
    std::size_t code_begin = 0, code_end = 0;
    /// Leaves: the leaf's number (-1 for operators).
    int leaf = -1;
    /// Operators: the items combined, all earlier than this one.
    std::vector<int> operands;
    /// Constant: its value.
    double value = 0.0;
    /// Ellipsoid, Segment: blob space to object space (the matrix given)
    /// and its inverse. Ellipsoids are the unit ball of blob space.
    Matrix4 to_object{1.0};
    Matrix4 to_blob{1.0};
    /// Segment: its ends and radius in blob space.
    glm::dvec3 start{0.0}, end{0.0};
    double radius = 1.0;
    /// GroundPlane: the depth map (a zfile or shadow map) whose surface
    /// repels, and A (the height above it where the field ends), B (the
    /// barrier's strength, -B/z), C (where the bulge peaks, over 2) and D
    /// (the bulge's height), as Application Note #31 defines them.
    std::string depth_map;
    std::array<double, 4> repel{};
};

/// A decoded, checked Blobby program.
struct BlobbyProgram {
    int leaves = 0;
    std::vector<BlobbyItem> items; ///< the last one is the field
};

/// An opcode that is not a RISpec Blobby opcode (nor one this toolchain
/// knows): its operands cannot even be counted. A ValueError, so callers
/// that do not single it out report it like any other malformed program.
class BlobbyOpcodeError : public ValueError {
public:
    BlobbyOpcodeError(const std::string& what, int opcode)
        : ValueError(what), m_opcode(opcode) {}
    int opcode() const { return m_opcode; }

private:
    int m_opcode;
};

/// Decodes `code` with its `floats` and `strings` and checks it: known
/// opcodes with all their operands, float and string indices in range,
/// operators naming earlier items (add, multiply, max and min at least
/// one), finite numbers, affine invertible matrices, segment radii > 0,
/// and `nleaf` equal to the number of primitive fields. Throws ValueError
/// "code[4]: ..." saying what is wrong where (BlobbyOpcodeError for an
/// unknown opcode). A ground plane's operands are its string (the depth
/// map) then its 4 floats, as PRMan's note gives them, or the other way
/// round, as RISpec's table does, whichever fits the arrays (the note's
/// when both do). Plugins are decoded (their operands checked) but not
/// evaluated by anyone: callers decide what to do.
BlobbyProgram decode_blobby(int nleaf, const std::vector<int>& code,
                            const std::vector<double>& floats,
                            const std::vector<std::string>& strings);

/// The program of a Blobby primitive (prim.nu, verts, args, tags).
inline BlobbyProgram decode_blobby(const Primitive& prim) {
    return decode_blobby(prim.nu, prim.verts, prim.args, prim.tags);
}

} // namespace sss
