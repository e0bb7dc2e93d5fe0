// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
/// \file outputs_test.cpp
/// Tests of output handling in sss/util: AtomicOutput onto symbolic links,
/// FIFOs and devices, stale temporaries of killed writers, OutputSet (all
/// outputs or none) and JobFiles (outputs over inputs).

#include <gtest/gtest.h>

#include <csignal>
#include <cstring>
#include <filesystem>
#include <string>
#include <thread>
#include <vector>

#include <fcntl.h>
#include <sys/file.h>
#include <sys/socket.h>
#include <sys/stat.h>
#include <sys/sysmacros.h>
#include <sys/un.h>
#include <sys/wait.h>
#include <unistd.h>

#include "sss/util/atomic_output.h"
#include "sss/util/error.h"
#include "sss/util/job_files.h"
#include "test_util.h"

namespace fs = std::filesystem;

namespace {

using sss::test::read_text;
using sss::test::TempDir;
using sss::test::write_text;

/// The part of a temporary's name after ".<name>.": "<host>.<pid>.<random>.tmp".
std::string owner_part(const std::string& temp, const std::string& name) {
    const std::string file = fs::path(temp).filename().string();
    return file.substr(name.size() + 2);
}

/// The host of a temporary name made for `name`.
std::string host_of(const std::string& temp, const std::string& name) {
    const std::string rest = owner_part(temp, name);
    return rest.substr(0, rest.find('.'));
}

/// A pid no process has: a child that has exited and been reaped.
pid_t dead_pid() {
    const pid_t child = ::fork();
    if (child == 0) ::_exit(0);
    int status = 0;
    ::waitpid(child, &status, 0);
    return child;
}

bool is_fifo(const std::string& path) {
    struct stat st {};
    return ::lstat(path.c_str(), &st) == 0 && S_ISFIFO(st.st_mode);
}

} // namespace

// ---------------------------------------------------------------------------
// Symbolic links
// ---------------------------------------------------------------------------

TEST(AtomicOutputTargets, SymlinkKeepsTheLinkAndReplacesItsFile) {
    TempDir dir;
    fs::create_directories(dir.path() / "real");
    const std::string file = dir.file("real/a.ptc");
    const std::string link = dir.file("a.ptc");
    write_text(file, "old");
    fs::create_symlink("real/a.ptc", link);
    {
        sss::AtomicOutput out(link);
        EXPECT_EQ(fs::path(out.temp_path()).parent_path(),
                  fs::canonical(dir.path() / "real"))
            << "the temporary is made next to the file the link names";
        write_text(out.temp_path(), "new");
        out.commit();
    }
    EXPECT_TRUE(fs::is_symlink(link));
    EXPECT_EQ(fs::read_symlink(link), fs::path("real/a.ptc"));
    EXPECT_EQ(read_text(file), "new");
    EXPECT_EQ(dir.entries(), (std::vector<std::string>{"a.ptc", "real"}));
}

TEST(AtomicOutputTargets, DanglingSymlinkCreatesTheFileItNames) {
    TempDir dir;
    fs::create_directories(dir.path() / "real");
    const std::string link = dir.file("a.ptc");
    fs::create_symlink("real/new.ptc", link);
    sss::AtomicOutput out(link);
    write_text(out.temp_path(), "made");
    out.commit();
    EXPECT_TRUE(fs::is_symlink(link));
    EXPECT_EQ(read_text(dir.file("real/new.ptc")), "made");
}

TEST(AtomicOutputTargets, SymlinkLoopIsAnError) {
    TempDir dir;
    fs::create_symlink("b", dir.path() / "a");
    fs::create_symlink("a", dir.path() / "b");
    EXPECT_THROW(sss::AtomicOutput out(dir.file("a")), sss::IoError);
    EXPECT_THROW(sss::check_output_target(dir.file("a")), sss::IoError);
}

// ---------------------------------------------------------------------------
// FIFOs and devices: written into, never renamed over
// ---------------------------------------------------------------------------

TEST(AtomicOutputTargets, FifoReceivesTheDataAndStaysAFifo) {
    TempDir dir;
    const std::string fifo = dir.file("out.ptc");
    ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0);
    std::string received;
    std::thread reader([&] { received = read_text(fifo); });
    {
        sss::AtomicOutput out(fifo);
        EXPECT_TRUE(out.writes_into());
        EXPECT_NE(fs::path(out.temp_path()).parent_path(), dir.path())
            << "the temporary of a FIFO is staged outside its folder";
        write_text(out.temp_path(), std::string(300000, 'x') + "end");
        out.commit();
        EXPECT_FALSE(fs::exists(out.temp_path()));
    }
    reader.join();
    EXPECT_EQ(received.size(), 300003u);
    EXPECT_EQ(received.substr(received.size() - 3), "end");
    EXPECT_TRUE(is_fifo(fifo));
    EXPECT_EQ(dir.entries(), std::vector<std::string>{"out.ptc"});
}

TEST(AtomicOutputTargets, FifoWithoutCommitGetsNothing) {
    TempDir dir;
    const std::string fifo = dir.file("out.ptc");
    ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0);
    std::string temp;
    {
        sss::AtomicOutput out(fifo); // no reader needed: nothing is opened
        temp = out.temp_path();
        write_text(temp, "partial");
    }
    EXPECT_FALSE(fs::exists(temp));
    EXPECT_TRUE(is_fifo(fifo));
}

TEST(AtomicOutputTargets, UnixSocketReceivesTheData) {
    TempDir dir;
    const std::string path = dir.file("out.sock");
    const int listener = ::socket(AF_UNIX, SOCK_STREAM, 0);
    ASSERT_GE(listener, 0);
    sockaddr_un addr{};
    addr.sun_family = AF_UNIX;
    ASSERT_LT(path.size(), sizeof addr.sun_path);
    std::memcpy(addr.sun_path, path.c_str(), path.size() + 1);
    ASSERT_EQ(::bind(listener, reinterpret_cast<const sockaddr*>(&addr), sizeof addr), 0);
    ASSERT_EQ(::listen(listener, 1), 0);
    std::string received;
    std::thread reader([&] {
        const int c = ::accept(listener, nullptr, nullptr);
        char buf[4096];
        ssize_t n;
        while ((n = ::read(c, buf, sizeof buf)) > 0) received.append(buf, std::size_t(n));
        ::close(c);
    });
    {
        sss::AtomicOutput out(path);
        EXPECT_TRUE(out.writes_into());
        write_text(out.temp_path(), "over the socket");
        out.commit();
    }
    reader.join();
    ::close(listener);
    EXPECT_EQ(received, "over the socket");
    struct stat st {};
    ASSERT_EQ(::lstat(path.c_str(), &st), 0);
    EXPECT_TRUE(S_ISSOCK(st.st_mode));
}

TEST(AtomicOutputTargets, CharacterDeviceStaysADevice) {
    // /dev/null itself is never the target: as root, a private node of the
    // same device in the test's folder; otherwise only the non-root case.
    TempDir dir;
    std::string device = dir.file("null");
    if (::geteuid() != 0 || ::mknod(device.c_str(), S_IFCHR | 0666, makedev(1, 3)) != 0)
        GTEST_SKIP() << "needs root to make a character device";
    {
        sss::AtomicOutput out(device);
        EXPECT_TRUE(out.writes_into());
        write_text(out.temp_path(), "discarded");
        out.commit();
    }
    struct stat st {};
    ASSERT_EQ(::lstat(device.c_str(), &st), 0);
    EXPECT_TRUE(S_ISCHR(st.st_mode));
    EXPECT_EQ(major(st.st_rdev), 1u);
    EXPECT_EQ(minor(st.st_rdev), 3u);
    EXPECT_EQ(dir.entries(), std::vector<std::string>{"null"});
}

TEST(AtomicOutputTargets, FullDeviceIsAnIoError) {
    if (::access("/dev/full", W_OK) != 0) GTEST_SKIP() << "no writable /dev/full";
    sss::AtomicOutput out("/dev/full");
    write_text(out.temp_path(), "data");
    EXPECT_THROW(out.commit(), sss::IoError);
}

// ---------------------------------------------------------------------------
// Stale temporaries
// ---------------------------------------------------------------------------

TEST(AtomicOutputStale, TemporaryOfAKilledWriterIsRemoved) {
    TempDir dir;
    const std::string target = dir.file("a.exr");
    std::string host;
    {
        sss::AtomicOutput probe(target);
        host = host_of(probe.temp_path(), "a.exr");
    }
    const std::string pid = std::to_string(dead_pid());
    const std::string stale = dir.file(".a.exr." + host + "." + pid + ".AbCd1234.tmp");
    // Same pattern, other targets or other hosts: not ours to remove.
    const std::string other_target =
        dir.file(".b.exr." + host + "." + pid + ".AbCd1234.tmp");
    const std::string other_host =
        dir.file(".a.exr.elsewhere-" + host + "." + pid + ".AbCd1234.tmp");
    const std::string old_style = dir.file(".a.exr.AbCd1234.tmp");
    for (const std::string& f : {stale, other_target, other_host, old_style})
        write_text(f, "x");

    sss::AtomicOutput out(target);
    EXPECT_FALSE(fs::exists(stale));
    EXPECT_TRUE(fs::exists(other_target));
    EXPECT_TRUE(fs::exists(other_host));
    EXPECT_TRUE(fs::exists(old_style));
}

TEST(AtomicOutputStale, LiveOrLockedTemporariesStay) {
    TempDir dir;
    const std::string target = dir.file("a.exr");
    std::string host;
    {
        sss::AtomicOutput probe(target);
        host = host_of(probe.temp_path(), "a.exr");
    }
    // pid 1 always lives; a dead pid whose file someone holds locked (a
    // writer in another pid namespace) is alive too.
    const std::string live = dir.file(".a.exr." + host + ".1.AbCd1234.tmp");
    const std::string locked =
        dir.file(".a.exr." + host + "." + std::to_string(dead_pid()) + ".WxYz9876.tmp");
    write_text(live, "x");
    write_text(locked, "x");
    const int fd = ::open(locked.c_str(), O_RDONLY);
    ASSERT_GE(fd, 0);
    ASSERT_EQ(::flock(fd, LOCK_EX), 0);

    sss::AtomicOutput first(target);  // a live writer of the same target
    sss::AtomicOutput second(target); // must not remove first's temporary
    EXPECT_TRUE(fs::exists(live));
    EXPECT_TRUE(fs::exists(locked));
    EXPECT_TRUE(fs::exists(first.temp_path()));
    ::close(fd);
}

// ---------------------------------------------------------------------------
// OutputSet: every output or none
// ---------------------------------------------------------------------------

TEST(OutputSet, NothingIsReplacedBeforeCommit) {
    TempDir dir;
    const std::string a = dir.file("a.exr"), b = dir.file("b.exr");
    write_text(a, "old a");
    {
        sss::OutputSet set;
        sss::AtomicOutput out(a);
        write_text(out.temp_path(), "new a");
        out.commit();
        EXPECT_EQ(read_text(a), "old a") << "handed to the set, not renamed";
        sss::AtomicOutput second(b);
        write_text(second.temp_path(), "new b");
        second.commit();
        EXPECT_EQ(set.targets(), (std::vector<std::string>{a, b}));
        set.commit();
    }
    EXPECT_EQ(read_text(a), "new a");
    EXPECT_EQ(read_text(b), "new b");
    EXPECT_EQ(dir.entries(), (std::vector<std::string>{"a.exr", "b.exr"}));
}

TEST(OutputSet, AFailureLeavesEveryTargetAsItWas) {
    TempDir dir;
    const std::string a = dir.file("a.exr"), b = dir.file("b.exr");
    write_text(a, "old a");
    write_text(b, "old b");
    try {
        sss::OutputSet set;
        sss::AtomicOutput out(a);
        write_text(out.temp_path(), "new a");
        out.commit();
        sss::AtomicOutput second(b);
        write_text(second.temp_path(), "half of b");
        throw std::runtime_error("the second writer failed");
    } catch (const std::runtime_error&) {
    }
    EXPECT_EQ(read_text(a), "old a");
    EXPECT_EQ(read_text(b), "old b");
    EXPECT_EQ(dir.entries(), (std::vector<std::string>{"a.exr", "b.exr"}));
}

TEST(OutputSet, NestedSetCommitsWithTheOuterOne) {
    TempDir dir;
    const std::string a = dir.file("a.ptc");
    sss::OutputSet outer;
    {
        sss::OutputSet inner;
        sss::AtomicOutput out(a);
        write_text(out.temp_path(), "a");
        out.commit();
        inner.commit();
    }
    EXPECT_FALSE(fs::exists(a));
    outer.commit();
    EXPECT_EQ(read_text(a), "a");
}

TEST(OutputSet, OneFileTwiceIsAnError) {
    TempDir dir;
    const std::string a = dir.file("a.ptc");
    fs::create_symlink("a.ptc", dir.path() / "link.ptc");
    write_text(a, "old");
    sss::OutputSet set;
    sss::AtomicOutput first(a);
    write_text(first.temp_path(), "1");
    first.commit();
    sss::AtomicOutput second(dir.file("link.ptc"));
    write_text(second.temp_path(), "2");
    EXPECT_THROW(second.commit(), sss::IoError);
}

// ---------------------------------------------------------------------------
// JobFiles: outputs over inputs
// ---------------------------------------------------------------------------

TEST(JobFiles, OutputOverAnInputNamesBothUses) {
    TempDir dir;
    write_text(dir.file("cube.obj"), "v 0 0 0\n");
    sss::JobFiles files;
    files.input(dir.file("cube.obj"), "ReadArchive \"cube.obj\" at scene.rib:3");
    try {
        files.output(dir.file("cube.obj"), "Display \"cube.obj\" (scene.rib:9)");
        FAIL() << "expected OutputConflictError";
    } catch (const sss::OutputConflictError& e) {
        EXPECT_EQ(std::string(e.what()),
                  "Display \"cube.obj\" (scene.rib:9) is an input of this job "
                  "(ReadArchive \"cube.obj\" at scene.rib:3)");
    }
}

TEST(JobFiles, SameFileThroughLinksAndPaths) {
    TempDir dir;
    const std::string real = dir.file("in.ptc");
    write_text(real, "x");
    fs::create_symlink("in.ptc", dir.path() / "soft.ptc");
    fs::create_hard_link(real, dir.path() / "hard.ptc");
    fs::create_directories(dir.path() / "sub");
    for (const std::string& alias :
         {dir.file("soft.ptc"), dir.file("hard.ptc"), dir.file("sub/../in.ptc")}) {
        sss::JobFiles files;
        files.input(real, "input");
        EXPECT_THROW(files.output(alias, "output"), sss::OutputConflictError) << alias;
    }
    // A name that does not exist yet: by its absolute path.
    sss::JobFiles files;
    files.output(dir.file("new.exr"), "Display \"new.exr\"");
    EXPECT_THROW(files.output(dir.file("sub/../new.exr"), "Display \"+new.exr\""),
                 sss::OutputConflictError);
    EXPECT_NO_THROW(files.output(dir.file("other.exr"), "Display \"other.exr\""));
    EXPECT_NO_THROW(files.input(real, "input"));
}

TEST(JobFiles, LookupsOpenedAtRunTimeAreChecked) {
    TempDir dir;
    EXPECT_EQ(sss::JobFiles::opened(dir.file("a.tx"), "texture lookup"), "")
        << "no current registry: nothing to check";
    sss::JobFiles files;
    EXPECT_EQ(sss::JobFiles::current(), &files);
    files.output(dir.file("out.exr"), "Display \"out.exr\" (scene.rib:2)");
    EXPECT_EQ(sss::JobFiles::opened(dir.file("out.exr"), "a texture lookup"),
              "Display \"out.exr\" (scene.rib:2) is an input of this job (a texture "
              "lookup)");
    EXPECT_EQ(sss::JobFiles::opened(dir.file("a.tx"), "a texture lookup"), "");
    // Recorded as an input: a later output of that file is refused.
    EXPECT_THROW(files.output(dir.file("a.tx"), "bake3d file \"a.tx\""),
                 sss::OutputConflictError);
    {
        sss::JobFilesScope scope;
        EXPECT_EQ(&scope.files(), &files) << "a scope uses the current registry";
    }
}

TEST(OutputNames, Extensions) {
    const std::vector<std::string> images = {".exr", ".tif", ".png"};
    EXPECT_TRUE(sss::has_extension_in("a.EXR", images));
    EXPECT_TRUE(sss::has_extension_in("dir.x/a.0001.png", images));
    EXPECT_FALSE(sss::has_extension_in("a.xyz", images));
    EXPECT_FALSE(sss::has_extension_in("a", images));
    EXPECT_EQ(sss::unknown_extension_text("out.xyz", "an image file", images),
              "'out.xyz' is not an image file name: its extension .xyz is not known "
              "(known: .exr, .tif, .png)");
    EXPECT_EQ(sss::unknown_extension_text("out", "a point cloud file",
                                          sss::point_cloud_extensions()),
              "'out' is not a point cloud file name: it has no extension (known: .ptc, "
              ".ply)");
}

TEST(CheckOutputTarget, RefusesFoldersAndMissingFolders) {
    TempDir dir;
    fs::create_directories(dir.path() / "sub");
    EXPECT_THROW(sss::check_output_target(dir.file("sub")), sss::IoError);
    EXPECT_THROW(sss::check_output_target(dir.file("missing/a.exr")), sss::IoError);
    EXPECT_NO_THROW(sss::check_output_target(dir.file("a.exr")));
    EXPECT_NO_THROW(sss::check_output_target("/dev/null"));
    EXPECT_TRUE(dir.entries() == std::vector<std::string>{"sub"});
}

TEST(Outputs, StandardOutputByAnyName) {
    // Whatever stdout is here (a pipe, a file), /dev/stdout and /proc/self/fd/1
    // name it; another file or a missing one does not.
    TempDir dir;
    EXPECT_TRUE(sss::is_standard_output("/dev/stdout"));
    EXPECT_TRUE(sss::is_standard_output("/proc/self/fd/1"));
    EXPECT_FALSE(sss::is_standard_output(dir.file("missing.png")));
    const std::string other = dir.file("other.png");
    std::FILE* f = std::fopen(other.c_str(), "w");
    ASSERT_NE(f, nullptr);
    std::fclose(f);
    EXPECT_FALSE(sss::is_standard_output(other));
}
