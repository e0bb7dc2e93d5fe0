// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
/// \file threads.cpp
/// Usable CPU count (affinity mask, cgroup v1/v2 quotas) and ThreadLimit.

#include "sss/util/threads.h"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <optional>
#include <sstream>
#include <string>
#include <vector>

#include <sched.h>
#include <unistd.h>

#include <oneapi/tbb/global_control.h>

#include "sss/util/parse.h"

namespace sss {

// ---------------------------------------------------------------------------
// Threads
// ---------------------------------------------------------------------------

namespace {

int affinity_cpu_count() {
    // Start with the fixed-size set and grow for machines with > 1024 CPUs.
    for (int ncpu = CPU_SETSIZE; ncpu <= (1 << 20); ncpu *= 4) {
        cpu_set_t* set = CPU_ALLOC(ncpu);
        if (!set) break;
        std::size_t bytes = CPU_ALLOC_SIZE(ncpu);
        CPU_ZERO_S(bytes, set);
        if (::sched_getaffinity(0, bytes, set) == 0) {
            int count = CPU_COUNT_S(bytes, set);
            CPU_FREE(set);
            return count;
        }
        int err = errno;
        CPU_FREE(set);
        if (err != EINVAL) break;
    }
    long n = ::sysconf(_SC_NPROCESSORS_ONLN);
    return n > 0 ? static_cast<int>(n) : 1;
}

std::optional<std::string> read_first_line(const std::string& path) {
    std::ifstream in(path);
    std::string line;
    if (!in || !std::getline(in, line)) return std::nullopt;
    return line;
}

// CPUs allowed by a quota/period pair; nullopt when unlimited or unreadable.
std::optional<int> quota_cpus(double quota, double period) {
    if (!(quota > 0.0) || !(period > 0.0)) return std::nullopt;
    return std::max(1, static_cast<int>(std::ceil(quota / period)));
}

// cgroup v2 "cpu.max": "<quota|max> <period>".
std::optional<int> read_cpu_max(const std::string& dir) {
    auto line = read_first_line(dir + "/cpu.max");
    if (!line) return std::nullopt;
    std::istringstream in(*line);
    std::string quota;
    double period = 0.0;
    if (!(in >> quota >> period) || quota == "max") return std::nullopt;
    auto q = parse_finite(quota);
    return q ? quota_cpus(*q, period) : std::nullopt;
}

// cgroup v1 "cpu.cfs_quota_us" (-1 = unlimited) and "cpu.cfs_period_us".
std::optional<int> read_cfs(const std::string& dir) {
    auto quota = read_first_line(dir + "/cpu.cfs_quota_us");
    auto period = read_first_line(dir + "/cpu.cfs_period_us");
    if (!quota || !period) return std::nullopt;
    auto q = parse_finite(*quota);
    auto p = parse_finite(*period);
    return (q && p) ? quota_cpus(*q, *p) : std::nullopt;
}

struct CgroupMount {
    std::string mount_point;
    std::string root;
};

std::optional<int> min_opt(std::optional<int> a, std::optional<int> b) {
    if (!a) return b;
    if (!b) return a;
    return std::min(*a, *b);
}

// Smallest quota on the way from the process's cgroup up to the mount point:
// a parent's quota limits every child.
template <typename Reader>
std::optional<int> walk_cgroup(const CgroupMount& mount, std::string cg_path,
                               Reader read) {
    // Inside a cgroup namespace the mount root is a prefix of our path.
    if (mount.root != "/" && cg_path.rfind(mount.root, 0) == 0)
        cg_path = cg_path.substr(mount.root.size());
    std::filesystem::path dir = std::filesystem::path(mount.mount_point);
    std::filesystem::path rel = std::filesystem::path(cg_path).relative_path();
    std::optional<int> best;
    std::vector<std::filesystem::path> chain{dir};
    for (const auto& part : rel) {
        if (part.empty()) continue;
        dir /= part;
        chain.push_back(dir);
    }
    for (const auto& d : chain) best = min_opt(best, read(d.string()));
    return best;
}

std::optional<int> cgroup_cpu_limit() {
    // Our cgroup paths: "0::/path" (v2) and "N:cpu,cpuacct:/path" (v1).
    std::optional<std::string> v2_path, v1_path;
    {
        std::ifstream in("/proc/self/cgroup");
        std::string line;
        while (std::getline(in, line)) {
            auto c1 = line.find(':');
            auto c2 = c1 == std::string::npos ? c1 : line.find(':', c1 + 1);
            if (c2 == std::string::npos) continue;
            std::string id = line.substr(0, c1);
            std::string ctrls = line.substr(c1 + 1, c2 - c1 - 1);
            std::string path = line.substr(c2 + 1);
            if (id == "0" && ctrls.empty()) {
                v2_path = path;
                continue;
            }
            std::istringstream cs(ctrls);
            std::string c;
            while (std::getline(cs, c, ','))
                if (c == "cpu") v1_path = path;
        }
    }
    // Mount points from mountinfo: "... root mountpoint opts ... - fstype src superopts".
    std::optional<CgroupMount> v2_mount, v1_mount;
    {
        std::ifstream in("/proc/self/mountinfo");
        std::string line;
        while (std::getline(in, line)) {
            auto sep = line.find(" - ");
            if (sep == std::string::npos) continue;
            std::istringstream pre(line.substr(0, sep));
            std::istringstream post(line.substr(sep + 3));
            std::string id, parent, devno, root, mount_point, fstype, source, superopts;
            if (!(pre >> id >> parent >> devno >> root >> mount_point)) continue;
            if (!(post >> fstype >> source >> superopts)) continue;
            if (fstype == "cgroup2" && !v2_mount) {
                v2_mount = CgroupMount{mount_point, root};
            } else if (fstype == "cgroup" && !v1_mount) {
                std::istringstream os(superopts);
                std::string o;
                while (std::getline(os, o, ','))
                    if (o == "cpu") v1_mount = CgroupMount{mount_point, root};
            }
        }
    }
    std::optional<int> limit;
    if (v2_path && v2_mount)
        limit = min_opt(limit, walk_cgroup(*v2_mount, *v2_path, read_cpu_max));
    if (v1_path && v1_mount)
        limit = min_opt(limit, walk_cgroup(*v1_mount, *v1_path, read_cfs));
    if (!v2_mount && !v1_mount) {
        // No readable mountinfo: try the usual locations.
        limit = min_opt(limit, read_cpu_max("/sys/fs/cgroup"));
        limit = min_opt(limit, read_cfs("/sys/fs/cgroup/cpu"));
        limit = min_opt(limit, read_cfs("/sys/fs/cgroup/cpu,cpuacct"));
    }
    return limit;
}

int usable_cpu_count() {
    int n = affinity_cpu_count();
    if (auto limit = cgroup_cpu_limit()) n = std::min(n, *limit);
    return std::max(1, n);
}

} // namespace

int resolve_thread_count(int requested) {
    if (requested > 0) return requested;
    int usable = usable_cpu_count();
    if (requested == 0) return usable;
    // requested < 0: all but |requested|; widen to avoid overflow at INT_MIN.
    long long n = static_cast<long long>(usable) + requested;
    return static_cast<int>(std::max<long long>(1, n));
}

struct ThreadLimit::Impl {
    explicit Impl(int n)
        : control(oneapi::tbb::global_control::max_allowed_parallelism,
                  static_cast<std::size_t>(n)) {}
    oneapi::tbb::global_control control;
};

// n < 1 follows the -threads rules (0 = usable CPUs, -k = all but k).
ThreadLimit::ThreadLimit(int n)
    : m_impl(std::make_unique<Impl>(n > 0 ? n : resolve_thread_count(n))) {}

ThreadLimit::~ThreadLimit() = default;

} // namespace sss
