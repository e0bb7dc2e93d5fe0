// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
/// \file job_files.cpp
/// The registry of a job's inputs and outputs (outputs over inputs are
/// refused) and the output-name checks.

#include "sss/util/job_files.h"

#include <algorithm>
#include <atomic>
#include <cctype>
#include <filesystem>

#include <sys/stat.h>

#include "sss/util/error.h"
#include "sss/util/messages.h"

namespace sss {

namespace {

std::atomic<JobFiles*> g_current{nullptr};
std::mutex g_current_mutex;

std::string lower(std::string s) {
    for (char& c : s) c = char(std::tolower(static_cast<unsigned char>(c)));
    return s;
}

} // namespace

bool JobFiles::Identity::same(const Identity& other) const {
    if (exists && other.exists) return device == other.device && inode == other.inode;
    return !canonical.empty() && canonical == other.canonical;
}

JobFiles::Identity JobFiles::identify(const std::string& path) {
    Identity id;
    struct stat st {};
    if (::stat(path.c_str(), &st) == 0) {
        id.exists = true;
        id.device = static_cast<unsigned long long>(st.st_dev);
        id.inode = static_cast<unsigned long long>(st.st_ino);
    }
    std::error_code ec;
    std::filesystem::path abs = std::filesystem::absolute(path, ec);
    if (ec) abs = path;
    std::filesystem::path canonical = std::filesystem::weakly_canonical(abs, ec);
    id.canonical = (ec ? abs.lexically_normal() : canonical).string();
    return id;
}

JobFiles::JobFiles() {
    std::lock_guard<std::mutex> lock(g_current_mutex);
    m_outer = g_current.load(std::memory_order_relaxed);
    g_current.store(this, std::memory_order_release);
}

JobFiles::~JobFiles() {
    std::lock_guard<std::mutex> lock(g_current_mutex);
    if (g_current.load(std::memory_order_relaxed) == this)
        g_current.store(m_outer, std::memory_order_release);
}

JobFiles* JobFiles::current() {
    return g_current.load(std::memory_order_acquire);
}

std::string JobFiles::conflict_of_input(const Identity& id,
                                        const std::string& use) const {
    for (const Entry& o : m_outputs)
        if (o.id.same(id)) return o.use + " is an input of this job (" + use + ")";
    return {};
}

void check_file_name(const std::string& path, const std::string& use) {
    if (path.find('\0') == std::string::npos) return;
    // Escaped: what() is a C string, which would end at the NUL.
    throw ValueError((use.empty() ? sss::quoted(path) : escape_control(use)) +
                     ": a file name cannot hold a NUL byte");
}

void JobFiles::input(const std::string& path, const std::string& use) {
    check_file_name(path, use);
    const Identity id = identify(path);
    std::lock_guard<std::mutex> lock(m_mutex);
    const std::string conflict = conflict_of_input(id, use);
    if (!conflict.empty()) throw OutputConflictError(conflict);
    m_inputs.push_back({id, use});
}

void JobFiles::output(const std::string& path, const std::string& use) {
    check_file_name(path, use);
    const Identity id = identify(path);
    std::lock_guard<std::mutex> lock(m_mutex);
    for (const Entry& i : m_inputs)
        if (i.id.same(id))
            throw OutputConflictError(use + " is an input of this job (" + i.use + ")");
    for (const Entry& o : m_outputs)
        if (o.id.same(id))
            throw OutputConflictError(use + " names the same file as " + o.use);
    m_outputs.push_back({id, use});
}

bool JobFiles::is_output(const std::string& path) {
    const Identity id = identify(path);
    std::lock_guard<std::mutex> lock(m_mutex);
    return std::any_of(m_outputs.begin(), m_outputs.end(),
                       [&](const Entry& o) { return o.id.same(id); });
}

bool JobFiles::same_file(const std::string& a, const std::string& b) {
    return identify(a).same(identify(b));
}

std::string JobFiles::opened(const std::string& path, const std::string& use) {
    if (path.find('\0') != std::string::npos)
        return escape_control(use) + ": a file name cannot hold a NUL byte";
    JobFiles* files = current();
    if (!files) return {};
    {
        std::lock_guard<std::mutex> lock(files->m_mutex);
        if (auto it = files->m_opened.find(path); it != files->m_opened.end())
            return it->second;
    }
    const Identity id = identify(path);
    std::lock_guard<std::mutex> lock(files->m_mutex);
    std::string conflict = files->conflict_of_input(id, use);
    if (conflict.empty()) files->m_inputs.push_back({id, use});
    files->m_opened.emplace(path, conflict);
    return conflict;
}

JobFilesScope::JobFilesScope() {
    m_files = JobFiles::current();
    if (!m_files) {
        m_own = std::make_unique<JobFiles>();
        m_files = m_own.get();
    }
}

bool has_extension_in(const std::string& path,
                      const std::vector<std::string>& extensions) {
    const std::string ext = lower(std::filesystem::path(path).extension().string());
    return std::any_of(extensions.begin(), extensions.end(),
                       [&](const std::string& e) { return lower(e) == ext; });
}

std::string unknown_extension_text(const std::string& path, const std::string& what,
                                   const std::vector<std::string>& extensions) {
    std::string list;
    for (const std::string& e : extensions) list += (list.empty() ? "" : ", ") + e;
    const std::string ext = std::filesystem::path(path).extension().string();
    return "'" + path + "' is not " + what + " name: " +
           (ext.empty() ? std::string("it has no extension")
                        : "its extension " + ext + " is not known") +
           " (known: " + list + ")";
}

const std::vector<std::string>& point_cloud_extensions() {
    static const std::vector<std::string> extensions = {".ptc", ".ply"};
    return extensions;
}

} // namespace sss
