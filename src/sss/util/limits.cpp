// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
/// \file limits.cpp
/// Resource limits, the memory budget and the job's current stage.

#include "sss/util/limits.h"

#include <sys/resource.h>
#include <unistd.h>

#include <array>
#include <atomic>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <fstream>
#include <mutex>
#include <sstream>

namespace sss {

namespace {

struct LimitInfo {
    const char* name;
    const char* what;
    uint64_t default_value;
};

// The defaults are far above what a real scene asks for and far below what
// makes a 2-core, 24 GB node hang or die: docs/limits.md says why each.
constexpr std::array<LimitInfo, static_cast<size_t>(Limit::Count_)> kLimits{{
    {"PRIMITIVE_VERTICES", "vertices in one primitive", 16'000'000},
    {"PRIMITIVE_MICROPOLYGONS", "micropolygons in one primitive", 200'000'000},
    {"SCENE_MICROPOLYGONS", "micropolygons in the scene", 1'000'000'000},
    {"ARCHIVE_DEPTH", "levels of nested archives", 32},
    {"STRING_LENGTH", "bytes in one string", 16u << 20},
    {"TOKEN_LENGTH", "bytes in one token", 1u << 16},
    {"IMAGE_PIXELS", "pixels in one image", 1u << 28},
    {"IMAGE_SIDE", "pixels across one image side", 1u << 16},
    {"BRICKS", "bricks in one brick map", 64'000'000},
    {"SHADER_OPERATIONS", "shader operations in one shading batch", 100'000'000},
    {"SHADER_STRING_LENGTH", "bytes in one shader string", 1u << 20},
    {"SHADER_ARRAY_LENGTH", "elements in one resizable array", 1'000'000},
    {"BAKE3D_POINTS", "bake3d points in one job", 1'000'000'000},
    {"BAKE3D_FILES", "bake3d files in one job", 4096},
}};

const LimitInfo& info(Limit which) {
    return kLimits.at(static_cast<size_t>(which));
}

std::array<std::atomic<uint64_t>, static_cast<size_t>(Limit::Count_)> g_overrides{};

/// "123", "1e9", "64M", "2G" -> value; nullopt-like 0 for anything else.
uint64_t parse_amount(const std::string& text) {
    if (text.empty()) return 0;
    char* end = nullptr;
    double v = std::strtod(text.c_str(), &end);
    if (end == text.c_str() || !std::isfinite(v) || v <= 0) return 0;
    std::string suffix(end);
    double scale = 1;
    if (suffix == "K" || suffix == "k")
        scale = 1024.0;
    else if (suffix == "M" || suffix == "m")
        scale = 1024.0 * 1024;
    else if (suffix == "G" || suffix == "g")
        scale = 1024.0 * 1024 * 1024;
    else if (suffix == "T" || suffix == "t")
        scale = 1024.0 * 1024 * 1024 * 1024;
    else if (!suffix.empty())
        return 0;
    double total = v * scale;
    if (total < 1 || total > 1.8e19) return 0;
    return static_cast<uint64_t>(total);
}

uint64_t env_amount(const std::string& variable) {
    const char* text = std::getenv(variable.c_str());
    if (!text) return 0;
    uint64_t v = parse_amount(text);
    if (v == 0)
        throw UsageError(variable + "=\"" + std::string(text) +
                         "\": expected a positive number (suffixes K, M, G allowed)");
    return v;
}

std::string format_count(uint64_t n) {
    return std::to_string(n);
}

// --- memory ----------------------------------------------------------------

uint64_t read_number_file(const std::string& path) {
    std::ifstream in(path);
    std::string word;
    if (!(in >> word) || word == "max") return 0;
    char* end = nullptr;
    unsigned long long v = std::strtoull(word.c_str(), &end, 10);
    if (end == word.c_str()) return 0;
    return v;
}

struct CgroupMemory {
    uint64_t max = 0;     // 0 = none
    uint64_t current = 0; // usage of the cgroup whose limit binds
};

/// The tightest memory limit of the cgroups above this process (v2), or
/// the v1 memory controller's.
CgroupMemory cgroup_memory() {
    CgroupMemory best;
    std::ifstream in("/proc/self/cgroup");
    std::string line;
    while (std::getline(in, line)) {
        auto c1 = line.find(':');
        auto c2 = c1 == std::string::npos ? c1 : line.find(':', c1 + 1);
        if (c2 == std::string::npos) continue;
        std::string id = line.substr(0, c1);
        std::string ctrls = line.substr(c1 + 1, c2 - c1 - 1);
        std::string path = line.substr(c2 + 1);
        std::string base;
        const char* max_file = nullptr;
        const char* cur_file = nullptr;
        if (id == "0" && ctrls.empty()) {
            base = "/sys/fs/cgroup";
            max_file = "memory.max";
            cur_file = "memory.current";
        } else if (ctrls.find("memory") != std::string::npos) {
            base = "/sys/fs/cgroup/memory";
            max_file = "memory.limit_in_bytes";
            cur_file = "memory.usage_in_bytes";
        } else {
            continue;
        }
        // Walk from our cgroup up to the root; inside a cgroup namespace the
        // path is "/" and the limit is at the mount point itself.
        std::string dir = path;
        while (true) {
            std::string full = base + (dir == "/" ? "" : dir);
            uint64_t max = read_number_file(full + "/" + max_file);
            // v1 reports "no limit" as a huge page-rounded number.
            if (max > 0 && max < (uint64_t(1) << 60) &&
                (best.max == 0 || max < best.max)) {
                best.max = max;
                best.current = read_number_file(full + "/" + cur_file);
            }
            if (dir == "/" || dir.empty()) break;
            auto slash = dir.rfind('/');
            dir = slash == 0 ? "/" : dir.substr(0, slash);
        }
    }
    return best;
}

uint64_t physical_memory() {
    long pages = sysconf(_SC_PHYS_PAGES);
    long page = sysconf(_SC_PAGESIZE);
    uint64_t total = pages > 0 && page > 0 ? uint64_t(pages) * uint64_t(page) : 0;
    std::ifstream in("/proc/meminfo");
    std::string key;
    uint64_t kb = 0;
    std::string unit;
    while (in >> key >> kb >> unit)
        if (key == "SwapTotal:") total += kb * 1024;
    return total;
}

uint64_t rlimit_bytes(int resource) {
    struct rlimit rl {};
    if (getrlimit(resource, &rl) != 0 || rl.rlim_cur == RLIM_INFINITY) return 0;
    return uint64_t(rl.rlim_cur);
}

// --- stages ----------------------------------------------------------------

std::mutex g_stage_mutex;

// Held for the whole process (never destroyed: a stage may end after exit
// handlers ran). The failure stage is the innermost stage an exception left.
std::string& stage_ref() {
    static std::string* stage = new std::string();
    return *stage;
}
std::string& failure_stage_ref() {
    static std::string* stage = new std::string();
    return *stage;
}

} // namespace

const char* limit_name(Limit which) {
    return info(which).name;
}
std::string limit_variable(Limit which) {
    return std::string("SSS_LIMIT_") + info(which).name;
}
const char* limit_what(Limit which) {
    return info(which).what;
}
uint64_t limit_default(Limit which) {
    return info(which).default_value;
}

uint64_t limit(Limit which) {
    uint64_t v =
        g_overrides.at(static_cast<size_t>(which)).load(std::memory_order_relaxed);
    if (v) return v;
    v = env_amount(limit_variable(which));
    return v ? v : limit_default(which);
}

void set_limit(Limit which, uint64_t value) {
    g_overrides.at(static_cast<size_t>(which)).store(value, std::memory_order_relaxed);
}

void check_limit(Limit which, uint64_t needed, const std::string& where) {
    uint64_t allowed = limit(which);
    if (needed <= allowed) return;
    throw LimitError(which, (where.empty() ? std::string() : where + ": ") +
                                format_count(needed) + " " + limit_what(which) +
                                " exceeds the limit of " + format_count(allowed) +
                                " (set " + limit_variable(which) + " to raise it)");
}

std::string limit_exceeded(Limit which) {
    return "exceeds the limit of " + format_count(limit(which)) + " (set " +
           limit_variable(which) + " to raise it)";
}

MemoryBudget usable_memory() {
    MemoryBudget budget;
    auto consider = [&](uint64_t bytes, const char* source) {
        if (bytes > 0 && (budget.bytes == 0 || bytes < budget.bytes)) {
            budget.bytes = bytes;
            budget.source = source;
        }
    };
    consider(env_amount("SSS_MEMORY_LIMIT"), "SSS_MEMORY_LIMIT");
    CgroupMemory cg = cgroup_memory();
    if (cg.max > 0) {
        // What the cgroup holds besides this process is not ours to use.
        uint64_t ours = resident_memory();
        uint64_t others = cg.current > ours ? cg.current - ours : 0;
        consider(cg.max > others ? cg.max - others : 1, "cgroup memory.max");
    }
    consider(rlimit_bytes(RLIMIT_AS), "ulimit -v");
    consider(rlimit_bytes(RLIMIT_DATA), "ulimit -d");
    consider(physical_memory(), "physical memory");
    return budget;
}

uint64_t resident_memory() {
    std::ifstream in("/proc/self/statm");
    uint64_t size = 0, resident = 0;
    if (!(in >> size >> resident)) return 0;
    long page = sysconf(_SC_PAGESIZE);
    return resident * uint64_t(page > 0 ? page : 4096);
}

uint64_t peak_resident_memory() {
    std::ifstream in("/proc/self/status");
    std::string line;
    while (std::getline(in, line))
        if (line.rfind("VmHWM:", 0) == 0) {
            unsigned long long kb = 0;
            if (std::sscanf(line.c_str() + 6, "%llu", &kb) == 1)
                return uint64_t(kb) * 1024;
        }
    return 0;
}

std::string format_bytes(uint64_t bytes) {
    const char* units[] = {"bytes", "KB", "MB", "GB", "TB", "PB"};
    double v = double(bytes);
    int u = 0;
    while (v >= 1024.0 && u < 5) v /= 1024.0, ++u;
    char text[64];
    if (u == 0)
        std::snprintf(text, sizeof text, "%llu bytes",
                      static_cast<unsigned long long>(bytes));
    else
        std::snprintf(text, sizeof text, v < 100 ? "%.1f %s" : "%.0f %s", v, units[u]);
    return text;
}

void check_memory(uint64_t needed_bytes, const std::string& what,
                  const std::string& remedy) {
    MemoryBudget budget = usable_memory();
    if (budget.bytes == 0) return;
    // RLIMIT_AS counts address space, not residency: compare the whole
    // process's size with it, the new need on top of what is resident.
    uint64_t in_use = resident_memory();
    if (needed_bytes <= budget.bytes && in_use <= budget.bytes - needed_bytes) return;
    throw OutOfMemoryError(what + " needs about " + format_bytes(needed_bytes + in_use) +
                           "; this process may use " + format_bytes(budget.bytes) + " (" +
                           budget.source + ")" + (remedy.empty() ? "" : "; " + remedy));
}

ScopedStage::ScopedStage(std::string stage) : m_uncaught(std::uncaught_exceptions()) {
    std::lock_guard<std::mutex> lock(g_stage_mutex);
    // A stage that begins after an exception left another one: that
    // exception was handled, and its stage names no later failure.
    failure_stage_ref().clear();
    std::string& current = stage_ref();
    m_previous = std::move(current);
    current = std::move(stage);
}

ScopedStage::~ScopedStage() {
    std::lock_guard<std::mutex> lock(g_stage_mutex);
    std::string& failed = failure_stage_ref();
    if (std::uncaught_exceptions() > m_uncaught && failed.empty()) failed = stage_ref();
    stage_ref() = std::move(m_previous);
}

std::string current_stage() {
    std::lock_guard<std::mutex> lock(g_stage_mutex);
    return stage_ref();
}

std::string failure_stage() {
    std::lock_guard<std::mutex> lock(g_stage_mutex);
    return failure_stage_ref().empty() ? stage_ref() : failure_stage_ref();
}

} // namespace sss
