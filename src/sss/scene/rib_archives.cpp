// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
/// \file rib_archives.cpp
/// The reader's files, frames and archives: RIB and OBJ files read through
/// ReadArchive or DelayedReadArchive, inline archives recorded and replayed,
/// and the FrameBegin blocks selected or skipped.

#include "rib_reader.h"

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "obj_import.h"
#include "rib_args.h"
#include "sss/util/byte_io.h"
#include "sss/util/limits.h"
#include "sss/util/messages.h"
#include "sss/util/subprocess.h"

namespace sss::rib {

namespace {

namespace fs = std::filesystem;

/// Statements replayed from inline archives (ReadArchive of an
/// ArchiveBegin block) in one scene: archives that each read the next one
/// twice double the work per level, and 32 levels would run for hours.
/// 10 million (about 1 s) are far more than a real scene replays; a reading
/// that would exceed them is refused before it starts (define_archive
/// counts what each archive replays).
constexpr uint64_t kMaxReplayedStatements = 10'000'000;

bool ends_with_obj(const std::string& path) {
    return path.size() >= 4 && lower(path.substr(path.size() - 4)) == ".obj";
}

} // namespace

std::string Reader::resolve_path(const Statement& s, const std::string& name,
                                 const char* kind) {
    fs::path p(name);
    if (p.is_absolute()) return name;
    const std::vector<std::string> path = search_path(m_scene, kind);
    if (auto found = find_on_search_path(path, name)) return *found;
    // As before search paths: the folder of the file that names it.
    const fs::path base = fs::path(*s.file).parent_path();
    const std::string beside = (base / p).lexically_normal().string();
    std::error_code ec;
    if (fs::exists(beside, ec)) return beside;
    // In the words of the other readers, then where it was looked for.
    throw IoError(name,
                  "cannot open: " + std::string(std::strerror(ENOENT)) +
                      " (not found along the " + kind + " search path \"" +
                      search_path_text(path) +
                      "\", relative to the working folder, nor beside " +
                      sss::quoted(*s.file) + "; " + s.name + " at " + where(s) + ")",
                  ENOENT);
}

// --- files -----------------------------------------------------------------

std::string file_key(const std::string& path) {
    std::error_code ec;
    fs::path p = fs::weakly_canonical(fs::path(path), ec);
    return ec ? fs::path(path).lexically_normal().string() : p.string();
}

void Reader::run_text(std::string_view text, std::shared_ptr<const std::string> path) {
    Lexer lexer(text, std::move(path));
    Statement st;
    while (lexer.next(st)) execute(st);
}

void Reader::check_archive_depth(const Statement& from, const std::string& name) {
    // Read once: replays of inline archives call this millions of times.
    if (m_max_depth == 0) m_max_depth = limit(Limit::ArchiveDepth);
    if (uint64_t(m_depth) + 1 > m_max_depth)
        check_limit(Limit::ArchiveDepth, uint64_t(m_depth) + 1,
                    where(from) + ": " + from.name + " " + sss::quoted(name));
}

void Reader::run_file(const Statement& from, const std::string& path) {
    // A file that reads itself (directly or through others) never ends:
    // RIB has no conditions that could stop it.
    const std::string key = file_key(path);
    for (std::size_t i = 0; i < m_reading.size(); ++i)
        if (m_reading[i].first == key) {
            std::string chain;
            for (std::size_t j = i; j < m_reading.size(); ++j)
                chain += truncated(m_reading[j].second, kMaxEcho) + " -> ";
            fail(from, sss::quoted(path) + " reads itself (" + chain +
                           truncated(path, kMaxEcho) + ")");
        }
    check_archive_depth(from, path);
    const bool obj = ends_with_obj(path);
    if (obj && !m_object && !m_in_world)
        fail(from, "geometry outside WorldBegin/WorldEnd");
    std::string text = slurp(path, " (ReadArchive at " + where(from) + ")");
    if (std::find(m_scene.sources.begin(), m_scene.sources.end(), path) ==
        m_scene.sources.end()) {
        m_scene.sources.push_back(path);
        m_scene.source_uses.push_back(from.name + " \"" + path + "\" at " + where(from));
    }
    ++m_depth;
    m_reading.emplace_back(key, path);
    if (obj)
        add_obj(text, path);
    else
        run_text(text, std::make_shared<const std::string>(path));
    m_reading.pop_back();
    --m_depth;
}

namespace {

/// All of a source's (inflated) bytes, the memory checked as the text grows:
/// a gzip RIB may inflate a thousandfold.
std::string read_all(detail::ByteSource& in) {
    std::string text;
    std::size_t size = 0;
    // A plain file in one block of its size (+1 to see the end at once).
    std::size_t first = 1u << 20;
    if (auto bound = in.remaining_bound(); bound && !in.compressed())
        first = static_cast<std::size_t>(*bound) + 1;
    for (;;) {
        if (text.size() == size) {
            const std::size_t want = text.empty() ? first : 2 * text.size();
            check_memory(want, "reading " + in.path(),
                         "split the scene into smaller archives");
            text.resize(want);
        }
        const std::size_t got = in.read(text.data() + size, text.size() - size);
        if (got == 0) break;
        size += got;
    }
    in.finish();
    text.resize(size);
    if (text.capacity() > size + size / 4) text.shrink_to_fit(); // an inflated stream
    return text;
}

} // namespace

std::string slurp(const std::string& path, const std::string& context) {
    detail::require_regular_file(path, context);
    detail::ByteSource in(path);
    return read_all(in);
}

std::string slurp_standard_input() {
    detail::ByteSource in{detail::ByteSource::StandardInput{}};
    return read_all(in);
}

// --- frames ----------------------------------------------------------------

void Reader::do_frame_begin(const Statement& s) {
    std::size_t i = 0;
    int number = to_int(s, take_number(s, i), "frame number");
    no_more_args(s, i);
    if (m_in_frame) fail(s, "nested FrameBegin");
    if (m_in_world) fail(s, "FrameBegin inside WorldBegin/WorldEnd");
    m_frames_seen = true;
    m_scene.frame_numbers.push_back(number);
    m_after_read_frame = false;
    bool wanted = !m_frame_read && (!m_options.frame || *m_options.frame == number);
    // The requests since the last frame run before this one, if it is read.
    if (wanted)
        for (MakeRequest& m : m_pending_makes) m_scene.makes.push_back(std::move(m));
    m_pending_makes.clear();
    if (!wanted) {
        m_skipping = true;
        m_skip_line = s.line;
        m_skip_file = s.file;
        return;
    }
    m_frame_read = true;
    m_in_frame = true;
    m_scene.options.frame = number;
    push(s, Block::Frame);
}

void Reader::do_frame_end(const Statement& s) {
    no_more_args(s, 0);
    if (!m_in_frame) fail(s, "FrameEnd without FrameBegin");
    SavedState saved = pop(s, Block::Frame);
    restore_all(saved);
    m_in_frame = false;
    m_after_read_frame = true; // only the frame read gets here (others are skipped)
}

// --- archives --------------------------------------------------------------

void Reader::do_archive_begin(const Statement& s) {
    std::size_t i = 0;
    m_record_name = take_string(s, i, "archive name");
    m_recording = true;
    m_record_depth = 0;
    m_record_line = s.line;
    m_record_file = s.file;
    m_record.clear();
}

void Reader::do_archive_end(const Statement& s) {
    fail(s, "ArchiveEnd without ArchiveBegin");
}

void Reader::define_archive(const std::string& name, std::vector<Statement> body) {
    // What reading it replays, known now for the archives it reads that are
    // defined already: an exponential nesting is refused before it runs.
    uint64_t replays = 0;
    for (const Statement& st : body) {
        uint64_t n = 1;
        if (st.name == "ReadArchive" && !st.args.empty() && st.args[0].is_string())
            if (auto it = m_archives.find(st.args[0].string); it != m_archives.end())
                n += it->second.replays;
        replays = std::min(replays + n, uint64_t(1) << 62);
    }
    m_archives[name] = {std::make_shared<const std::vector<Statement>>(std::move(body)),
                        replays};
}

void Reader::read_archive(const Statement& s, const std::string& name) {
    auto it = m_archives.find(name);
    if (it != m_archives.end()) {
        check_archive_depth(s, name);
        if (m_replayed + it->second.replays > kMaxReplayedStatements)
            fail(s, sss::quoted(name) + " replays " + std::to_string(it->second.replays) +
                        " statements from inline archives, more than " +
                        std::to_string(kMaxReplayedStatements) +
                        " in one scene (archives that read others several times grow "
                        "exponentially with their nesting)");
        m_replayed += it->second.body->size();
        // What the replayed statements make (primitives) is in no other
        // estimate: check the memory every million statements.
        if (m_replayed >= m_next_replay_check) {
            check_memory(kMemoryCheckStep,
                         where(s) + ": ReadArchive " + sss::quoted(name) + " (" +
                             std::to_string(m_replayed) +
                             " statements replayed from inline archives)",
                         "read fewer inline archives");
            m_next_replay_check = m_replayed + 1'000'000;
        }
        // Held: the archive may be redefined while it is replayed.
        const std::shared_ptr<const std::vector<Statement>> body = it->second.body;
        ++m_depth;
        for (const Statement& st : *body) execute(st);
        --m_depth;
        return;
    }
    run_file(s, resolve_path(s, name));
}

void Reader::do_read_archive(const Statement& s) {
    std::size_t i = 0;
    std::string name = take_string(s, i, "archive file name");
    take_params(s, i, true);
    read_archive(s, name);
}

void Reader::do_procedural(const Statement& s) {
    std::size_t i = 0;
    std::string kind = take_string(s, i, "procedural name");
    if (kind != "DelayedReadArchive" && kind != "RunProgram" && kind != "DynamicLoad") {
        not_implemented("procedural " + kind, s,
                        "Procedural " + sss::quoted(kind) + " is not supported",
                        "skipped");
        return;
    }
    auto args = take_string_array(s, i, "procedural arguments");
    auto bound = take_float_array(s, i, "bound");
    no_more_args(s, i);
    if (kind == "DelayedReadArchive" && args.size() != 1)
        fail(s, "DelayedReadArchive needs exactly one file name");
    if (kind != "DelayedReadArchive" && args.size() != 2)
        fail(s, kind + " needs two strings: the " +
                    (kind == "RunProgram" ? "program" : "DSO") + " and its data");
    if (bound.size() != 6) fail(s, "bound must have 6 numbers");
    // A procedural runs in a copy of the graphics state.
    push(s, Block::Attribute);
    if (kind == "RunProgram")
        run_program(s, args[0], args[1], bound);
    else if (kind == "DynamicLoad")
        dynamic_load(s, args[0], args[1], bound);
    else
        read_archive(s, args[0]);
    SavedState saved = pop(s, Block::Attribute);
    restore_all(saved);
}

double Reader::raster_area(const std::vector<double>& bound) const {
    // The bound's corners in raster space; a bound reaching behind the eye
    // (or without a camera) asks for all the detail there is.
    const Camera& cam = m_scene.options.camera;
    const Matrix4 to_ndc = cam.world_to_ndc() * m_ctm;
    double lo[2] = {1e300, 1e300}, hi[2] = {-1e300, -1e300};
    for (int c = 0; c < 8; ++c) {
        const glm::dvec4 h = to_ndc * glm::dvec4(bound[c & 1], bound[2 + ((c >> 1) & 1)],
                                                 bound[4 + ((c >> 2) & 1)], 1.0);
        if (!(h.w > 0.0)) return 1e30;
        for (int k = 0; k < 2; ++k) {
            lo[k] = std::min(lo[k], h[k] / h.w);
            hi[k] = std::max(hi[k], h[k] / h.w);
        }
    }
    const double area = (hi[0] - lo[0]) * cam.xres * (hi[1] - lo[1]) * cam.yres;
    return std::isfinite(area) ? std::min(area, 1e30) : 1e30;
}

void Reader::run_program(const Statement& s, const std::string& command,
                         const std::string& data, const std::vector<double>& bound) {
    std::vector<std::string> argv;
    std::istringstream words(command);
    for (std::string w; words >> w;) argv.push_back(w);
    if (argv.empty()) fail(s, "RunProgram: no program named");
    // The program is looked for along the procedural search path, then PATH.
    if (argv[0].find('/') == std::string::npos)
        if (auto found =
                find_on_search_path(search_path(m_scene, "procedural"), argv[0])) {
            argv[0] = found->find('/') == std::string::npos ? "./" + *found : *found;
            if (std::find(m_scene.sources.begin(), m_scene.sources.end(), *found) ==
                m_scene.sources.end()) {
                m_scene.sources.push_back(*found);
                m_scene.source_uses.push_back("Procedural \"RunProgram\" at " + where(s));
            }
        }
    check_archive_depth(s, argv[0]);
    // RiProcedural's protocol: a request "detail datablock" on a line; the
    // RIB answer ends with the byte 0377.
    char detail[64];
    std::snprintf(detail, sizeof detail, "%.9g ", raster_area(bound));
    const std::string answer =
        run_filter(argv, detail + data + "\n", 0377, FilterLimits{},
                   where(s) + ": Procedural \"RunProgram\"");
    check_memory(answer.size(), "reading the answer of " + argv[0], "");
    ++m_depth;
    run_text(answer, std::make_shared<const std::string>(argv[0] + " (RunProgram at " +
                                                         where(s) + ")"));
    --m_depth;
}

void Reader::do_make_texture(const Statement& s) {
    std::size_t i = 0;
    MakeRequest m;
    m.kind = s.name;
    m.input = take_string(s, i, "picture name");
    m.output = take_string(s, i, "texture name");
    if (s.name == "MakeTexture") {
        m.swrap = take_string(s, i, "swrap");
        m.twrap = take_string(s, i, "twrap");
    }
    m.filter = take_string(s, i, "filter");
    m.swidth = take_number(s, i);
    m.twidth = take_number(s, i);
    m.params = take_params(s, i, false);
    if (!(m.swidth > 0.0) || !(m.twidth > 0.0)) fail(s, "filter widths must be > 0");
    if (m.output.empty()) fail(s, "no texture name");
    if (auto found = find_on_search_path(search_path(m_scene, "texture"), m.input))
        m.input = *found;
    m.source = where(s);
    add_make(std::move(m));
}

void Reader::add_make(MakeRequest m) {
    // After the world read was rendered: a zfile it wrote exists by then.
    const bool world_done = m_scene.worlds > 0 && !m_in_world;
    if (m_in_frame) {
        m.after_frame = world_done;
        m_scene.makes.push_back(std::move(m));
    } else if (m_after_read_frame || (!m_frames_seen && world_done)) {
        // Without frames the requests before the world are the scene's:
        // they keep their place in RIB order.
        if (!m_frames_seen) {
            for (MakeRequest& p : m_pending_makes) m_scene.makes.push_back(std::move(p));
            m_pending_makes.clear();
        }
        m.after_frame = true;
        m_scene.makes.push_back(std::move(m));
    } else if (!m_frame_read) {
        m_pending_makes.push_back(std::move(m));
    }
    // Else it lies between two frames not read: theirs.
}

void Reader::do_make_shadow(const Statement& s) {
    std::size_t i = 0;
    MakeRequest m;
    m.kind = s.name;
    m.input = take_string(s, i, "zfile name");
    m.output = take_string(s, i, "shadow map name");
    m.params = take_params(s, i, false);
    if (m.input.empty()) fail(s, "no zfile name");
    if (m.output.empty()) fail(s, "no shadow map name");
    // The zfile is often rendered by an earlier frame of this very file: a
    // name found nowhere yet is kept as given (relative to the working folder).
    if (auto found = find_on_search_path(search_path(m_scene, "texture"), m.input))
        m.input = *found;
    m.source = where(s);
    add_make(std::move(m));
}

void Reader::do_make_cube_face_environment(const Statement& s) {
    std::size_t i = 0;
    MakeRequest m;
    m.kind = s.name;
    static const char* const kFaces[6] = {"px", "nx", "py", "ny", "pz", "nz"};
    for (const char* face : kFaces) {
        std::string name =
            take_string(s, i, (std::string(face) + " picture name").c_str());
        if (name.empty()) fail(s, std::string("no ") + face + " picture name");
        if (auto found = find_on_search_path(search_path(m_scene, "texture"), name))
            name = *found;
        m.faces.push_back(std::move(name));
    }
    m.input = m.faces[0];
    m.output = take_string(s, i, "texture name");
    m.fov = take_number(s, i);
    m.filter = take_string(s, i, "filter");
    m.swidth = take_number(s, i);
    m.twidth = take_number(s, i);
    m.params = take_params(s, i, false);
    if (m.output.empty()) fail(s, "no texture name");
    if (!(m.fov > 0.0 && m.fov < 180.0))
        fail(s, "field of view must be in (0, 180) degrees");
    if (!(m.swidth > 0.0) || !(m.twidth > 0.0)) fail(s, "filter widths must be > 0");
    m.source = where(s);
    add_make(std::move(m));
}

void Reader::add_obj(const std::string& text, const std::string& path) {
    std::vector<std::string> warnings;
    auto mesh = detail::import_obj(text, path, warnings);
    for (std::string& w : warnings) m_scene.warnings.push_back(std::move(w));
    if (!mesh) return;
    Statement at;
    at.name = "ReadArchive";
    at.file = std::make_shared<const std::string>(path);
    at.line = mesh->first_face_line;
    add_primitive(at, std::move(mesh->primitive), Matrix4(1.0),
                  path + ":" + std::to_string(mesh->first_face_line));
}

} // namespace sss::rib
