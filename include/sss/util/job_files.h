// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
#pragma once
/// \file job_files.h
/// What one job (one tool run) reads and writes, so that no output replaces
/// one of the job's inputs or another of its outputs, and the output-name
/// checks shared by the tools (docs/cli-conventions.md, "Outputs").

#include <memory>
#include <mutex>
#include <string>
#include <unordered_map>
#include <vector>

#include "sss/util/error.h"

namespace sss {

/// An output that names one of the job's inputs, or a file the job already
/// writes. Exit status 1.
class OutputConflictError : public Error {
public:
    explicit OutputConflictError(const std::string& what) : Error(what) {}
};

/// The files of a job and how each is used ("ReadArchive \"cube.obj\" at
/// scene.rib:3", "Display \"out.exr\" (scene.rib:9)"). Two names are the
/// same file when both exist with the same device and inode (symbolic and
/// hard links included), or when their absolute paths, with the symbolic
/// links of their existing part resolved, are equal.
///
/// The registry made last and still alive is the current one: lookups the
/// shaders open while the job runs (textures, point clouds, brick maps)
/// are checked against it through opened().
class JobFiles {
public:
    JobFiles();
    ~JobFiles();
    JobFiles(const JobFiles&) = delete;
    JobFiles& operator=(const JobFiles&) = delete;

    /// The current registry, or null.
    static JobFiles* current();

    /// Records an input. Throws OutputConflictError when it is one of the
    /// outputs: "<output use> is an input of this job (<input use>)".
    void input(const std::string& path, const std::string& use);
    /// Records an output. Throws OutputConflictError when it is an input, or
    /// an output recorded before ("<use> names the same file as <earlier use>").
    void output(const std::string& path, const std::string& use);
    /// Whether `path` is the same file as a recorded output.
    bool is_output(const std::string& path);
    /// Whether two names are the same file (by the rule above).
    static bool same_file(const std::string& a, const std::string& b);

    /// For a file a shader opens while the job runs: records it as an input
    /// of the current registry and returns "" or, when it is one of the
    /// job's outputs or holds a NUL byte, the error text (the caller fails the
    /// lookup with it). Each name is checked once. Thread-safe; without a
    /// current registry only the NUL is checked.
    static std::string opened(const std::string& path, const std::string& use);

private:
    struct Identity {
        bool exists = false;
        unsigned long long device = 0, inode = 0;
        std::string canonical;
        bool same(const Identity& other) const;
    };
    struct Entry {
        Identity id;
        std::string use;
    };
    static Identity identify(const std::string& path);
    std::string conflict_of_input(const Identity& id, const std::string& use) const;

    std::mutex m_mutex;
    std::vector<Entry> m_inputs;
    std::vector<Entry> m_outputs;
    std::unordered_map<std::string, std::string> m_opened; ///< name -> error text
    JobFiles* m_outer = nullptr;
};

/// The current JobFiles, or one of its own made current for its lifetime:
/// what a library entry point (render_scene, bake_scene) records into.
class JobFilesScope {
public:
    JobFilesScope();
    JobFiles& files() { return *m_files; }

private:
    std::unique_ptr<JobFiles> m_own;
    JobFiles* m_files = nullptr;
};

/// Whether `path` ends in one of `extensions` (".exr"; compared ignoring case).
bool has_extension_in(const std::string& path,
                      const std::vector<std::string>& extensions);

/// "'out.xyz' is not a <what> name: its extension is not one of .ptc, .ply"
/// (or "it has no extension"), for unknown-extension errors.
std::string unknown_extension_text(const std::string& path, const std::string& what,
                                   const std::vector<std::string>& extensions);

/// The extensions of the point cloud formats written (.ptc, .ply).
const std::vector<std::string>& point_cloud_extensions();

/// Throws ValueError when `path` holds a NUL byte, which the system would
/// take for the end of the name (`"x\0y.ptc"` would open `x`). `use` says
/// what the name is ("bake3d file ..."); empty: the quoted name.
void check_file_name(const std::string& path, const std::string& use = "");

} // namespace sss
