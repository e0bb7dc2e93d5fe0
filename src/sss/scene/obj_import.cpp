// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
/// \file obj_import.cpp
/// Wavefront OBJ import: logical lines (with '\' continuations and '#'
/// comments), vertices, normals and texture coordinates, faces with their
/// 1-based or negative (from the end) indices, gathered into one mesh.

#include "obj_import.h"

#include <algorithm>
#include <charconv>
#include <set>

#include "rib_lexer.h"
#include "sss/scene/rib.h"
#include "sss/util/limits.h"

namespace sss::detail {

namespace {

/// The state of one import: what the lines read so far defined.
class ObjReader {
public:
    ObjReader(std::string_view text, const std::string& path,
              std::vector<std::string>& warnings)
        : m_text(text), m_path(path), m_warnings(warnings) {}

    std::optional<ObjMesh> read() {
        std::string line;
        while (next_line(line)) {
            if (std::size_t hash = line.find('#'); hash != std::string::npos)
                line.resize(hash);
            std::vector<std::string_view> words = split(line);
            if (words.empty()) continue;
            m_key = std::string(words[0]);
            statement(words);
        }
        if (m_degenerate_faces > 0)
            m_warnings.push_back(m_path + ": " + std::to_string(m_degenerate_faces) +
                                 (m_degenerate_faces == 1 ? " face" : " faces") +
                                 " with fewer than 3 distinct corners left out");
        if (m_nverts.empty()) {
            m_warnings.push_back(m_path + ": no faces, nothing imported");
            return std::nullopt;
        }
        return mesh();
    }

private:
    [[noreturn]] void fail(const std::string& what) const {
        throw RibError(m_path, m_start_line, m_key, what);
    }

    /// One logical line: a trailing backslash continues it. False at the end.
    bool next_line(std::string& line) {
        if (m_pos >= m_text.size()) return false;
        line.clear();
        ++m_line_no;
        m_start_line = m_line_no;
        for (;;) {
            std::size_t end = m_text.find('\n', m_pos);
            if (end == std::string::npos) end = m_text.size();
            std::string_view part(m_text.data() + m_pos, end - m_pos);
            m_pos = std::min(end + 1, m_text.size() + 1);
            if (!part.empty() && part.back() == '\r') part.remove_suffix(1);
            if (!part.empty() && part.back() == '\\' && m_pos <= m_text.size()) {
                part.remove_suffix(1);
                line.append(part);
                line.push_back(' ');
                ++m_line_no;
                continue;
            }
            line.append(part);
            return true;
        }
    }

    static std::vector<std::string_view> split(const std::string& line) {
        std::vector<std::string_view> words;
        std::size_t k = 0;
        while (k < line.size()) {
            while (k < line.size() && rib::is_space(line[k])) ++k;
            std::size_t b = k;
            while (k < line.size() && !rib::is_space(line[k])) ++k;
            if (k > b) words.emplace_back(line.data() + b, k - b);
        }
        return words;
    }

    double number(std::string_view w) const {
        double d;
        std::string err;
        if (!rib::parse_number(w, d, err)) fail(err);
        return d;
    }

    void statement(const std::vector<std::string_view>& words) {
        const std::string& key = m_key;
        if (key == "v") {
            std::size_t n = words.size() - 1;
            if (n != 3 && n != 4 && n != 6)
                fail("expected x y z [w] (or x y z r g b), got " + std::to_string(n) +
                     " numbers");
            for (std::size_t k = 1; k <= n; ++k) {
                double d = number(words[k]);
                if (k <= 3) m_positions.push_back(d); // w and colours are not used
            }
        } else if (key == "vn") {
            if (words.size() != 4)
                fail("expected 3 numbers, got " + std::to_string(words.size() - 1));
            for (std::size_t k = 1; k <= 3; ++k) m_normals.push_back(number(words[k]));
        } else if (key == "vt") {
            for (std::size_t k = 1; k < words.size(); ++k) number(words[k]);
            ++m_texcoords;
        } else if (key == "f") {
            face(words);
        } else if (key == "g" || key == "o" || key == "s" || key == "usemtl" ||
                   key == "mtllib" || key == "l") {
            // grouping, smoothing, materials and lines carry nothing for us
        } else if (m_warned.insert(key).second) {
            m_warnings.push_back(m_path + ":" + std::to_string(m_start_line) +
                                 ": unsupported OBJ statement '" + key + "', skipped");
        }
    }

    /// A 1-based index, or a negative one relative to the end, among `count`
    /// defined so far; 0-based.
    int index(std::string_view w, long count, const char* what) const {
        long k = 0;
        auto r = std::from_chars(w.data(), w.data() + w.size(), k);
        if (r.ec != std::errc() || r.ptr != w.data() + w.size())
            fail(std::string("malformed ") + what + " index '" + std::string(w) + "'");
        if (k == 0) fail(std::string(what) + " index 0 (OBJ counts from 1)");
        long resolved = k > 0 ? k - 1 : count + k; // negative: relative to the end
        if (resolved < 0 || resolved >= count)
            fail(std::string(what) + " index " + std::to_string(k) + " out of range (" +
                 std::to_string(count) + " defined)");
        return static_cast<int>(resolved);
    }

    /// "f v[/[t][/n]] ...": the vertices, and the normal of each corner (-1: none).
    void face(const std::vector<std::string_view>& words) {
        if (words.size() < 4)
            fail("a face needs at least 3 vertices, got " +
                 std::to_string(words.size() - 1));
        // Limit::PrimitiveVertices: for the face, and for the mesh's corners
        // so far (the mesh is one primitive), before they are stored.
        const std::string here = m_path + ":" + std::to_string(m_start_line) + ": f";
        check_limit(Limit::PrimitiveVertices, words.size() - 1, here);
        check_limit(Limit::PrimitiveVertices, m_verts.size() + words.size() - 1,
                    here + " (the mesh's face corners so far)");
        if (!m_first_face_line) m_first_face_line = m_start_line;
        const long nv_now = static_cast<long>(m_positions.size() / 3);
        const long nn_now = static_cast<long>(m_normals.size() / 3);
        const long nt_now = static_cast<long>(m_texcoords);
        for (std::size_t k = 1; k < words.size(); ++k) {
            std::string_view w = words[k];
            std::size_t s1 = w.find('/');
            std::string_view vpart = w.substr(0, s1);
            m_verts.push_back(index(vpart, nv_now, "vertex"));
            int normal = -1;
            if (s1 != std::string_view::npos) {
                std::string_view rest = w.substr(s1 + 1);
                std::size_t s2 = rest.find('/');
                std::string_view tpart = rest.substr(0, s2);
                if (!tpart.empty()) index(tpart, nt_now, "texture");
                if (s2 != std::string_view::npos) {
                    std::string_view npart = rest.substr(s2 + 1);
                    if (!npart.empty()) normal = index(npart, nn_now, "normal");
                }
            }
            if (normal < 0) m_all_normals = false;
            m_corner_normals.push_back(normal);
        }
        const std::size_t kept = clean_face(m_verts.size() - (words.size() - 1));
        if (kept >= 3)
            m_nverts.push_back(static_cast<int>(kept));
        else
            ++m_degenerate_faces;
    }

    /// Drops what a face (its corners from `first` on) repeats: a corner on
    /// the same vertex as the one before it (the last one's too, against
    /// the first), and the whole outline walked again, which would count
    /// its area once per walk. Returns how many corners are kept (fewer
    /// than 3: none, the face has no area).
    std::size_t clean_face(std::size_t first) {
        std::size_t n = first;
        for (std::size_t k = first; k < m_verts.size(); ++k)
            if (n == first || m_verts[k] != m_verts[n - 1]) {
                m_verts[n] = m_verts[k];
                m_corner_normals[n] = m_corner_normals[k];
                ++n;
            }
        while (n - first > 1 && m_verts[n - 1] == m_verts[first]) --n;
        std::size_t count = n - first;
        // The shortest period that repeats to the whole outline.
        for (std::size_t period = 1; period <= count / 2; ++period) {
            if (count % period) continue;
            bool repeats = true;
            for (std::size_t k = period; k < count && repeats; ++k)
                repeats = m_verts[first + k] == m_verts[first + k % period];
            if (repeats) {
                count = period;
                break;
            }
        }
        if (count < 3) count = 0;
        m_verts.resize(first + count);
        m_corner_normals.resize(first + count);
        return count;
    }

    ObjMesh mesh() {
        ObjMesh out;
        out.first_face_line = m_first_face_line;
        Primitive& p = out.primitive;
        p.kind = PrimitiveKind::PointsPolygons;
        std::size_t used = static_cast<std::size_t>(
            *std::max_element(m_verts.begin(), m_verts.end()) + 1);
        Param P;
        P.name = "P";
        P.type = ParamType::Point;
        P.storage = ParamClass::Vertex;
        // Vertices after the last one used are dropped: the count is max index + 1.
        P.numbers.assign(m_positions.begin(),
                         m_positions.begin() + static_cast<long>(3 * used));
        p.params.items.push_back(std::move(P));
        if (m_all_normals) {
            Param N;
            N.name = "N";
            N.type = ParamType::Normal;
            N.storage = ParamClass::FaceVarying;
            N.numbers.reserve(3 * m_corner_normals.size());
            for (int n : m_corner_normals)
                for (int c = 0; c < 3; ++c)
                    N.numbers.push_back(m_normals[static_cast<std::size_t>(3 * n + c)]);
            p.params.items.push_back(std::move(N));
        }
        p.nverts = std::move(m_nverts);
        p.verts = std::move(m_verts);
        return out;
    }

    std::string_view m_text;
    const std::string& m_path;
    std::vector<std::string>& m_warnings;
    std::size_t m_pos = 0;
    int m_line_no = 0;
    int m_start_line = 0; // first line of the logical line being read
    std::string m_key;    // its keyword, for messages
    std::vector<double> m_positions, m_normals;
    std::size_t m_texcoords = 0;
    std::vector<int> m_nverts, m_verts, m_corner_normals;
    bool m_all_normals = true;
    int m_first_face_line = 0;
    std::size_t m_degenerate_faces = 0;
    std::set<std::string> m_warned;
};

} // namespace

std::optional<ObjMesh> import_obj(std::string_view text, const std::string& path,
                                  std::vector<std::string>& warnings) {
    return ObjReader(text, path, warnings).read();
}

} // namespace sss::detail
