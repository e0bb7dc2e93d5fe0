// libFuzzer target: the PLY reader (ours and foreign files, binary and
// ASCII), then the checks of fuzz_cloud.h plus a PLY write and read back.
// docs/fuzzing.md.

#include "fuzz_cloud.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    static const sss::fuzz::ScratchFile in("ply_in", ".ply");
    static const sss::fuzz::ScratchFile out("ply_out", ".ptc");
    static const sss::fuzz::ScratchFile out_ply("ply_out", ".ply");
    in.write(data, size);
    sss::fuzz::run_expecting_errors([&] {
        const sss::PointCloud cloud = sss::read_ply(in.path());
        sss::fuzz::exercise_cloud(cloud, out);
        // Our own PLY writer may refuse channel names whose components clash
        // with other properties (a ValueError, documented); when it writes,
        // the file must read back with the same points.
        bool written = false;
        try {
            sss::write_ply(cloud, out_ply.path());
            written = true;
        } catch (const sss::ValueError&) {
        }
        if (!written) return;
        sss::PointCloud back;
        try {
            back = sss::read_ply(out_ply.path());
        } catch (const std::exception& e) {
            sss::fuzz::finding(std::string("our own PLY does not read back: ") +
                               e.what());
        }
        sss::fuzz::require(back.size() == cloud.size() &&
                               back.channels.size() == cloud.channels.size(),
                           "PLY write + read back changed the counts");
    });
    return 0;
}
