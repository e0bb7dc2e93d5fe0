// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
// Sanitizer settings of the SSS_SANITIZE build (docs/testing.md), compiled
// into every executable of that build only, so that the tools check the same
// way however they are started (CTest, the CLI test scripts, scenes/*/run, by
// hand).
//
// Default options: ASAN_OPTIONS and UBSAN_OPTIONS in the environment are
// applied on top. exitcode=99: a report must never pass for a tool's own
// failure exit (1, or 2 for usage errors), which the CLI tests expect.
//
// Death marks: when SSS_SANITIZER_MARKS names a folder, a process that dies of
// a report (AddressSanitizer, LeakSanitizer or UndefinedBehaviorSanitizer)
// first leaves a file there holding its command line. tests/cli/sanitized.sh
// fails a CLI test on any mark, even when the script discarded the tool's
// stderr (where the report goes) or ignored its exit status.

#include <dlfcn.h>
#include <fcntl.h>
#include <link.h>
#include <sanitizer/common_interface_defs.h>
#include <unistd.h>

#include <cstdio>
#include <cstdlib>
#include <cstring>

// The runtime calls these hooks before it is set up: no instrumentation.
#define SSS_SANITIZER_HOOK                                                               \
    extern "C" __attribute__((used, visibility("default"),                               \
                              no_sanitize("address", "undefined")))

SSS_SANITIZER_HOOK const char* __asan_default_options() {
    // new_delete_type_mismatch=0: OpenImageIO 2.4's TextureSystem::destroy
    // frees its implementation through the base class with a sized delete
    // (Debian's libOpenImageIO, not our code), which this check reports.
    return "halt_on_error=1:exitcode=99:abort_on_error=0:detect_leaks=1:"
           "check_initialization_order=1:strict_init_order=1:"
           "detect_stack_use_after_return=1:print_stacktrace=1:"
           "new_delete_type_mismatch=0";
}

// OpenImageIO 2.4 keeps per-thread texture tiles of threads that ended until
// the process exits (Debian's libOpenImageIO): not ours.
SSS_SANITIZER_HOOK const char* __lsan_default_suppressions() {
    return "leak:libOpenImageIO.so\nleak:libOpenImageIO_Util.so\n";
}

SSS_SANITIZER_HOOK const char* __ubsan_default_options() {
    return "halt_on_error=1:exitcode=99:print_stacktrace=1";
}

namespace {

// Runs inside the dying runtime: plain system calls, no allocation.
void leave_death_mark() {
    const char* dir = std::getenv("SSS_SANITIZER_MARKS");
    if (dir == nullptr || *dir == '\0') return;
    char path[4096];
    int n =
        std::snprintf(path, sizeof path, "%s/mark.%d", dir, static_cast<int>(getpid()));
    if (n <= 0 || n >= static_cast<int>(sizeof path)) return;
    int out = open(path, O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
    if (out < 0) return;
    // The command line, arguments separated by spaces.
    char cmd[4096];
    ssize_t len = 0;
    int in = open("/proc/self/cmdline", O_RDONLY | O_CLOEXEC);
    if (in >= 0) {
        len = read(in, cmd, sizeof cmd - 1);
        close(in);
    }
    if (len < 0) len = 0;
    for (ssize_t i = 0; i < len; ++i)
        if (cmd[i] == '\0') cmd[i] = ' ';
    cmd[len] = '\n';
    ssize_t written = write(out, cmd, static_cast<std::size_t>(len) + 1);
    (void)written;
    close(out);
}

// With gcc, -fsanitize=address,undefined loads two runtimes (libasan.so and
// libubsan.so), each with its own death callback: set it in every sanitizer
// runtime loaded, not only in the one the symbol binds to. (clang, which
// scripts/test builds this with, links one static runtime: the direct call
// below covers it and the walk finds nothing.)
int set_death_callback_in(dl_phdr_info* info, std::size_t, void*) {
    const char* name = info->dlpi_name;
    if (name == nullptr || std::strstr(name, "san.so") == nullptr) return 0;
    if (void* lib = dlopen(name, RTLD_NOW | RTLD_NOLOAD)) {
        using SetCallback = void (*)(void (*)());
        if (auto set = reinterpret_cast<SetCallback>(
                dlsym(lib, "__sanitizer_set_death_callback")))
            set(leave_death_mark);
        dlclose(lib);
    }
    return 0;
}

__attribute__((constructor)) void install_death_mark() {
    __sanitizer_set_death_callback(leave_death_mark);
    dl_iterate_phdr(set_death_callback_in, nullptr);
}

} // namespace
