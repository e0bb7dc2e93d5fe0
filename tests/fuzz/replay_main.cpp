// A standalone driver for the libFuzzer targets (docs/fuzzing.md): linked
// with a target's LLVMFuzzerTestOneInput in the normal build (g++, Release or
// ASan/UBSan), it runs the target once on every file it is given (folders:
// every regular file below them, in name order), with the same checks as
// under libFuzzer: an sss::Error is a clean rejection, anything else aborts.
// ctest runs it as fuzz_replay.<target> over the committed corpus, the
// inputs the fuzzers found and the regressions.
//
//   fuzz_replay_<target> FILE|FOLDER...
//
// Files named "open-*" are findings in code not fixed yet: listed, not run.
// Exit 0 when every input ran (at least one), 1 when there was nothing to run
// or a path is unreadable; a finding aborts with the input's name printed.

#include <algorithm>
#include <chrono>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>
#include <vector>

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size);

namespace fs = std::filesystem;

int main(int argc, char** argv) {
    std::vector<fs::path> files;
    for (int i = 1; i < argc; ++i) {
        // Absolute now: targets may change the current directory.
        const fs::path arg = fs::absolute(argv[i]);
        std::error_code ec;
        if (fs::is_directory(arg, ec)) {
            for (const auto& e : fs::recursive_directory_iterator(arg))
                if (e.is_regular_file()) files.push_back(e.path());
        } else if (fs::is_regular_file(arg, ec)) {
            files.push_back(arg);
        } else if (fs::exists(arg, ec)) {
            std::fprintf(stderr, "replay: %s is not a file or folder\n", argv[i]);
            return 1;
        }
        // A missing folder is allowed: not every target has regressions.
    }
    std::sort(files.begin(), files.end());
    std::size_t ran = 0, open = 0;
    const auto start = std::chrono::steady_clock::now();
    for (const fs::path& p : files) {
        if (p.filename().string().rfind("open-", 0) == 0) {
            std::fprintf(stderr, "replay: skipped (open finding): %s\n", p.c_str());
            ++open;
            continue;
        }
        std::ifstream in(p, std::ios::binary);
        const std::vector<char> bytes((std::istreambuf_iterator<char>(in)),
                                      std::istreambuf_iterator<char>());
        if (!in.good() && !in.eof()) {
            std::fprintf(stderr, "replay: cannot read %s\n", p.c_str());
            return 1;
        }
        // Named first, so that a crash or a finding shows which input it was.
        std::fprintf(stderr, "replay: %s\n", p.c_str());
        std::fflush(stderr);
        LLVMFuzzerTestOneInput(reinterpret_cast<const uint8_t*>(bytes.data()),
                               bytes.size());
        ++ran;
    }
    const double seconds =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    std::printf("replay: %zu inputs in %.2f s (%zu open findings skipped)\n", ran,
                seconds, open);
    if (ran == 0) {
        std::fprintf(stderr, "replay: no input found\n");
        return 1;
    }
    return 0;
}
