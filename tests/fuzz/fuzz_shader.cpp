// libFuzzer target: the RSL compiler front end (lexer, parser, checker,
// code generator) on the input as preprocessed text, then the .slo writer
// and reader on every shader it compiles (the round trip must succeed and
// reproduce the same text). Inputs that start with "sss-slo" go to the .slo
// reader instead, which must reject damage cleanly. docs/fuzzing.md.
//
// The preprocessor is not run: #include could read files outside the corpus.
//
// In the fuzzing build, a custom mutator changes RSL text a token at a time
// (rsl_mutator.h) three times in four, and leaves the rest (and .slo inputs)
// to libFuzzer's byte-level mutation.

#include <cstring>
#include <random>
#include <sstream>
#include <string>

#include "fuzz_common.h"
#include "rsl_mutator.h"
#include "sss/rsl/compiler.h"
#include "sss/rsl/program.h"

namespace {

sss::PreprocessResult as_preprocessed(const std::string& text) {
    sss::PreprocessResult r;
    r.text = text;
    r.files = {"fuzz.sl"};
    int lines = 1;
    for (char c : text) lines += c == '\n';
    for (int i = 0; i < lines; ++i) r.lines.push_back({0, i + 1});
    return r;
}

void round_trip(const sss::Program& program) {
    std::ostringstream out;
    sss::write_program(program, out);
    std::istringstream in(out.str());
    sss::Program back;
    try {
        back = sss::read_program(in, "fuzz.slo");
    } catch (const sss::Error& e) {
        sss::fuzz::finding(std::string("a compiled program does not read back: ") +
                           e.what());
    }
    std::ostringstream again;
    sss::write_program(back, again);
    sss::fuzz::require(again.str() == out.str(), ".slo round trip changed the program");
}

} // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    if (size > 64 * 1024) return 0; // keeps every run short
    const std::string text(reinterpret_cast<const char*>(data), size);
    if (text.rfind("sss-slo", 0) == 0) {
        sss::fuzz::run_expecting_errors([&] {
            std::istringstream in(text);
            const sss::Program p = sss::read_program(in, "fuzz.slo");
            round_trip(p);
        });
        return 0;
    }
    sss::fuzz::run_expecting_errors([&] {
        const sss::CompileResult result =
            sss::compile_preprocessed(as_preprocessed(text));
        for (const sss::Program& p : result.shaders) round_trip(p);
    });
    return 0;
}

#ifdef SSS_LIBFUZZER
extern "C" size_t LLVMFuzzerMutate(uint8_t* data, size_t size, size_t max_size);

extern "C" size_t LLVMFuzzerCustomMutator(uint8_t* data, size_t size, size_t max_size,
                                          unsigned int seed) {
    std::minstd_rand rng(seed);
    const std::string_view in(reinterpret_cast<const char*>(data), size);
    if (rng() % 4 == 0 || in.rfind("sss-slo", 0) == 0)
        return LLVMFuzzerMutate(data, size, max_size);
    std::string text(in);
    // Now and then several changes at once, as libFuzzer stacks mutations.
    const int rounds = 1 + static_cast<int>(rng() % 3);
    bool changed = false;
    for (int r = 0; r < rounds; ++r) changed |= sss::fuzz::mutate_rsl(text, rng);
    if (!changed || text.size() > max_size) return LLVMFuzzerMutate(data, size, max_size);
    std::memcpy(data, text.data(), text.size());
    return text.size();
}
#endif
