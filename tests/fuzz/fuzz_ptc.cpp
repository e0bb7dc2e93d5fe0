// libFuzzer target: the .ptc reader (plain or gzip), then the checks of
// fuzz_cloud.h on whatever it accepts. docs/fuzzing.md.

#include "fuzz_cloud.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    static const sss::fuzz::ScratchFile in("ptc_in", ".ptc");
    static const sss::fuzz::ScratchFile out("ptc_out", ".ptc");
    in.write(data, size);
    sss::fuzz::run_expecting_errors([&] {
        const sss::PointCloud cloud = sss::read_ptc(in.path());
        sss::fuzz::exercise_cloud(cloud, out);
    });
    return 0;
}
