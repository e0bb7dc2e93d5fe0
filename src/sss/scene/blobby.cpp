// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
/// \file blobby.cpp
/// Decoding and checking of Blobby programs (blobby.h).

#include "sss/scene/blobby.h"

#include <cmath>
#include <string>

#include <glm/matrix.hpp>

namespace sss {

namespace {

/// One opcode's name and the number of operands that follow it; -1: a
/// count comes first, then that many items.
struct OpcodeInfo {
    int opcode;
    BlobbyOp op;
    const char* name;
    int operands;
};

constexpr OpcodeInfo kOpcodes[] = {
    {0, BlobbyOp::Add, "add", -1},
    {1, BlobbyOp::Multiply, "multiply", -1},
    {2, BlobbyOp::Max, "max", -1},
    {3, BlobbyOp::Min, "min", -1},
    {4, BlobbyOp::Subtract, "subtract", 2},
    {5, BlobbyOp::Divide, "divide", 2},
    {6, BlobbyOp::Negate, "negate", 1},
    {7, BlobbyOp::Identity, "identity", 1},
    {1000, BlobbyOp::Constant, "constant", 1},
    {1001, BlobbyOp::Ellipsoid, "ellipsoid", 1},
    {1002, BlobbyOp::Segment, "segment", 1},
    {1003, BlobbyOp::GroundPlane, "repelling ground plane", 2},
    {1004, BlobbyOp::Plugin, "implicit field plugin", 5},
};

const OpcodeInfo* find_opcode(int opcode) {
    for (const OpcodeInfo& o : kOpcodes)
        if (o.opcode == opcode) return &o;
    return nullptr;
}

/// Reads one program; every error names the code entry it is about.
class Decoder {
public:
    Decoder(const std::vector<int>& code, const std::vector<double>& floats,
            const std::vector<std::string>& strings)
        : m_code(code), m_floats(floats), m_strings(strings) {}

    BlobbyProgram run(int nleaf) {
        BlobbyProgram program;
        std::size_t at = 0;
        while (at < m_code.size()) {
            BlobbyItem item = next(at, program);
            if (blobby_is_leaf(item.op)) item.leaf = program.leaves++;
            program.items.push_back(std::move(item));
        }
        if (program.items.empty()) throw ValueError("the code array is empty");
        if (program.leaves != nleaf)
            throw ValueError("nleaf is " + std::to_string(nleaf) + " but the code has " +
                             std::to_string(program.leaves) + " primitive fields");
        return program;
    }

private:
    [[noreturn]] void fail(std::size_t at, const std::string& what) const {
        throw ValueError("code[" + std::to_string(at) + "]: " + what);
    }

    /// The operand after `at`, which must exist.
    int operand(std::size_t at, std::size_t k, const OpcodeInfo& info) const {
        if (at + k >= m_code.size())
            fail(at, std::string(info.name) + " (" + std::to_string(info.opcode) +
                         ") is cut short: the code ends before its operands");
        return m_code[at + k];
    }

    /// `count` floats from index `first`, all finite.
    const double* floats(std::size_t at, int first, int count, const char* what) const {
        if (first < 0 ||
            static_cast<std::size_t>(first) + static_cast<std::size_t>(count) >
                m_floats.size())
            fail(at, std::string(what) + " needs " + std::to_string(count) +
                         " floats from index " + std::to_string(first) +
                         ", but there are " + std::to_string(m_floats.size()));
        const double* f = m_floats.data() + first;
        for (int k = 0; k < count; ++k)
            if (!std::isfinite(f[k]))
                fail(at, std::string(what) + ": float " + std::to_string(first + k) +
                             " is not a finite number");
        return f;
    }

    void check_string(std::size_t at, int index, const char* what) const {
        if (index < 0 || static_cast<std::size_t>(index) >= m_strings.size())
            fail(at, std::string(what) + ": string index " + std::to_string(index) +
                         " out of range (" + std::to_string(m_strings.size()) +
                         " strings)");
    }

    /// A 4x4 blob-to-object matrix in RIB layout: affine and invertible.
    void matrix(std::size_t at, const double* f, const char* what,
                BlobbyItem& item) const {
        if (f[3] != 0.0 || f[7] != 0.0 || f[11] != 0.0 || f[15] == 0.0)
            fail(at, std::string(what) +
                         ": the matrix must be affine (its last column 0 0 0 w, w != 0)");
        Matrix4 m(1.0);
        for (int k = 0; k < 16; ++k) m[k / 4][k % 4] = f[k] / f[15];
        m[3][3] = 1.0;
        const double det = glm::determinant(glm::dmat3(m));
        const Matrix4 inverse = glm::inverse(m);
        bool finite_inverse = std::isfinite(det) && det != 0.0;
        for (int c = 0; c < 4 && finite_inverse; ++c)
            for (int r = 0; r < 4; ++r)
                finite_inverse = finite_inverse && std::isfinite(inverse[c][r]);
        if (!finite_inverse) fail(at, std::string(what) + ": the matrix is singular");
        item.to_object = m;
        item.to_blob = inverse;
    }

    BlobbyItem next(std::size_t& at, const BlobbyProgram& program) const {
        const int opcode = m_code[at];
        const OpcodeInfo* info = find_opcode(opcode);
        if (!info)
            throw BlobbyOpcodeError("code[" + std::to_string(at) + "]: unknown opcode " +
                                        std::to_string(opcode),
                                    opcode);
        BlobbyItem item;
        item.op = info->op;
        item.code_begin = at;
        const auto self = static_cast<int>(program.items.size());
        if (info->operands < 0) {
            const int count = operand(at, 1, *info);
            if (count < 1)
                fail(at, std::string(info->name) + " needs at least one operand, not " +
                             std::to_string(count));
            for (int k = 0; k < count; ++k)
                item.operands.push_back(
                    operand(at, 2 + static_cast<std::size_t>(k), *info));
            at += 2 + static_cast<std::size_t>(count);
        } else if (!blobby_is_leaf(info->op)) {
            for (int k = 0; k < info->operands; ++k)
                item.operands.push_back(
                    operand(at, 1 + static_cast<std::size_t>(k), *info));
            at += 1 + static_cast<std::size_t>(info->operands);
        }
        for (int o : item.operands)
            if (o < 0 || o >= self)
                fail(item.code_begin, std::string(info->name) + ": operand " +
                                          std::to_string(o) +
                                          " is not an earlier item (this is item " +
                                          std::to_string(self) + ")");
        if (blobby_is_leaf(info->op)) leaf(at, *info, item);
        item.code_end = at;
        return item;
    }

    /// A primitive field's operands; moves `at` past them.
    void leaf(std::size_t& at, const OpcodeInfo& info, BlobbyItem& item) const {
        const std::size_t begin = at;
        std::vector<int> ops;
        for (int k = 0; k < info.operands; ++k)
            ops.push_back(operand(at, 1 + static_cast<std::size_t>(k), info));
        at += 1 + static_cast<std::size_t>(info.operands);
        switch (info.op) {
        case BlobbyOp::Constant:
            item.value = floats(begin, ops[0], 1, info.name)[0];
            break;
        case BlobbyOp::Ellipsoid:
            matrix(begin, floats(begin, ops[0], 16, info.name), info.name, item);
            break;
        case BlobbyOp::Segment: {
            const double* f = floats(begin, ops[0], 23, info.name);
            item.start = glm::dvec3(f[0], f[1], f[2]);
            item.end = glm::dvec3(f[3], f[4], f[5]);
            item.radius = f[6];
            if (!(item.radius > 0.0))
                fail(begin,
                     "segment: the radius must be > 0, not " + std::to_string(f[6]));
            matrix(begin, f + 7, info.name, item);
            break;
        }
        case BlobbyOp::GroundPlane: {
            // Application Note #31 (PRMan) gives the depth map's string first,
            // RISpec's table the floats first: the order whose indices are
            // both in range, the note's when both are.
            const bool note_order =
                ops[0] >= 0 && std::size_t(ops[0]) < m_strings.size() && ops[1] >= 0 &&
                std::size_t(ops[1]) + 4 <= m_floats.size();
            const int string_at = note_order ? ops[0] : ops[1];
            const int floats_at = note_order ? ops[1] : ops[0];
            check_string(begin, string_at, info.name);
            const double* f = floats(begin, floats_at, 4, info.name);
            item.depth_map = m_strings[static_cast<std::size_t>(string_at)];
            item.repel = {f[0], f[1], f[2], f[3]};
            if (item.depth_map.empty())
                fail(begin, "repelling ground plane: no depth map named");
            break;
        }
        case BlobbyOp::Plugin:
            check_string(begin, ops[0], info.name);
            if (ops[1] < 0) fail(begin, "implicit field plugin: negative float count");
            if (ops[1] > 0) floats(begin, ops[2], ops[1], info.name);
            if (ops[3] < 0 || ops[4] < 0 ||
                static_cast<std::size_t>(ops[3]) + static_cast<std::size_t>(ops[4]) >
                    m_strings.size())
                fail(begin, "implicit field plugin: " + std::to_string(ops[3]) +
                                " strings from index " + std::to_string(ops[4]) +
                                " are not all there (" +
                                std::to_string(m_strings.size()) + " strings)");
            break;
        default:
            break;
        }
    }

    const std::vector<int>& m_code;
    const std::vector<double>& m_floats;
    const std::vector<std::string>& m_strings;
};

} // namespace

const char* blobby_op_name(BlobbyOp op) {
    for (const OpcodeInfo& o : kOpcodes)
        if (o.op == op) return o.name;
    return "?";
}

BlobbyProgram decode_blobby(int nleaf, const std::vector<int>& code,
                            const std::vector<double>& floats,
                            const std::vector<std::string>& strings) {
    return Decoder(code, floats, strings).run(nleaf);
}

} // namespace sss
