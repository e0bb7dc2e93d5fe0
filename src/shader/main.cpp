// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
/// \file main.cpp
/// shader: compiles RenderMan Shading Language sources (.sl) into .slo
/// files, as PRMan's `shader` does: the C preprocessor first (-I, -D, -U),
/// then one `<shadername>.slo` per shader in the current folder.

#include <filesystem>
#include <iostream>
#include <string>
#include <vector>

#include "sss/cli/tool.h"
#include "sss/rsl/compiler.h"
#include "sss/rsl/preprocess.h"
#include "sss/rsl/program.h"
#include "sss/util/atomic_output.h"
#include "sss/util/error.h"
#include "sss/util/job_files.h"
#include "sss/util/limits.h"
#include "sss/util/messages.h"

namespace {

const char* const kTool = "shader";

const char* const kUsage = R"(usage: shader [options] file.sl...

Compiles RenderMan Shading Language files. Each shader a file defines is
written to <shadername>.slo in the current folder (named after the shader,
not the file). Errors are printed as file:line:column with the source line.

options:
  -o file.slo    output file (one input file defining one shader); -o -src
                 names each .slo after its source file (a.sl -> a.slo),
                 -o -shader after the shader (the default)
  -I dir         add dir to the #include search path (also -Idir)
  -D name[=val]  define a macro (val defaults to 1; also -Dname[=val])
  -U name        undefine a macro (also -Uname)
  -C             keep comments in the preprocessor's output (as cpp -C);
                 the .slo is the same
  -nosd          accepted, as PRMan's shader takes it; the .slo is the same
  -q             quiet: no progress lines, no warnings
  -check         check the command line only, reading and writing
                 no file: exit 0 if it would run, 2 if not
  -h, --help     this help
  --version      version information

Exit codes: 0 ok, 1 a file did not compile or could not be written,
2 bad command line.
)";

// -X value or -Xvalue.
std::string attached_or_next(sss::ArgScanner& scan, const std::string& opt) {
    if (opt.size() > 1) return opt.substr(1);
    return scan.value(opt);
}

void add_define(sss::PreprocessOptions& options, const std::string& def) {
    const std::size_t eq = def.find('=');
    const std::string name = def.substr(0, eq);
    if (name.empty()) throw sss::UsageError("option -D needs a macro name");
    options.defines.emplace_back(name,
                                 eq == std::string::npos ? "1" : def.substr(eq + 1));
}

/// One compiled source: the files it read and the shaders it defines.
struct Compiled {
    std::string file;
    std::vector<std::string> read; ///< the source, then its #includes
    std::vector<sss::Program> shaders;
};

// "1 error in a.sl".
std::string errors_in(int errors, const std::string& file) {
    return std::to_string(errors) + (errors == 1 ? " error in " : " errors in ") + file;
}

// Compiles one file; prints its diagnostics (compiler style: file:line:col,
// the source line and a caret, which editors parse). Returns "" or what
// failed, for the one ERROR line at the end.
std::string compile_one(const std::string& file, const sss::PreprocessOptions& options,
                        const std::string& output, bool quiet,
                        std::vector<Compiled>& compiled) {
    sss::CompileResult result;
    std::vector<std::string> read;
    sss::flush_standard_output(); // keeps merged logs in order
    // Outside the try: a file that does not compile ends the stage normally
    // (the stage an exception leaves is the one an out-of-memory names).
    sss::ScopedStage stage("compiling " + file);
    try {
        sss::PreprocessResult source = sss::preprocess_file(file, options);
        read = source.files;
        result = sss::compile_preprocessed(source);
    } catch (const sss::ShaderCompileError& e) {
        int errors = 0;
        for (const sss::Diagnostic& d : e.diagnostics()) {
            if (d.severity == sss::Diagnostic::Severity::Error)
                ++errors;
            else if (quiet)
                continue;
            std::cerr << d.format() << "\n";
        }
        return errors_in(errors, file);
    } catch (const sss::PreprocessError& e) {
        // what() is "file:line:column: message": print it as the compiler's.
        const std::string where = e.file() + ":" + std::to_string(e.line()) + ":" +
                                  std::to_string(e.column()) + ": ";
        std::string message = e.what();
        if (message.rfind(where, 0) == 0) message = message.substr(where.size());
        std::cerr << where << "error: " << message << "\n";
        if (!e.source_line().empty())
            std::cerr << "  " << e.source_line() << "\n  "
                      << std::string(e.column() > 0 ? e.column() - 1 : 0, ' ') << "^\n";
        return errors_in(1, file);
    }
    if (!quiet)
        for (const sss::Diagnostic& w : result.warnings) std::cerr << w.format() << "\n";
    if (result.shaders.empty()) return file + ": defines no shader";
    if (!output.empty() && result.shaders.size() > 1)
        return file + ": defines " + std::to_string(result.shaders.size()) +
               " shaders but -o names one output";
    compiled.push_back({file, std::move(read), std::move(result.shaders)});
    return "";
}

int run(const std::vector<std::string>& args) {
    sss::PreprocessOptions options;
    std::string output;
    bool quiet = false;
    std::vector<std::string> files;

    sss::ArgScanner scan(args);
    std::string opt;
    while (scan.next_option(opt, files)) {
        if (sss::standard_option(kTool, opt, kUsage)) {
            return 0;
        } else if (opt == "o") {
            // PRMan's special names look like options.
            const std::string& next = scan.peek();
            output =
                next == "-src" || next == "-shader" ? scan.positional() : scan.value(opt);
        } else if (opt == "q") {
            quiet = true;
        } else if (opt == "C" || opt == "nosd") {
            // Options of PRMan's compiler that change nothing written here:
            // scripts that pass them compile unchanged.
        } else if (opt[0] == 'I') {
            options.include_dirs.push_back(attached_or_next(scan, opt));
        } else if (opt[0] == 'D') {
            add_define(options, attached_or_next(scan, opt));
        } else if (opt[0] == 'U') {
            options.undefines.push_back(attached_or_next(scan, opt));
        } else {
            throw sss::unknown_option(opt, kUsage);
        }
    }
    if (files.empty()) throw sss::UsageError("missing input file");
    // PRMan's special output names: -shader is the default naming, -src
    // names each .slo after its source.
    const bool by_source = output == "-src";
    if (output == "-shader" || by_source) output.clear();
    if (!output.empty() && files.size() > 1)
        throw sss::UsageError("-o names one output: give one input file");
    if (sss::check_only()) return 0;

    // Every file compiles before any .slo is written: all of them, or none.
    std::vector<std::string> failed;
    std::vector<Compiled> compiled;
    for (const std::string& file : files) {
        const std::string what =
            compile_one(file, options, by_source ? "-o -src" : output, quiet, compiled);
        if (!what.empty()) failed.push_back(what);
    }
    if (!failed.empty()) {
        std::string all;
        for (const std::string& f : failed) all += (all.empty() ? "" : "; ") + f;
        throw sss::ValueError(all + (compiled.empty() ? "" : "; nothing was written"));
    }
    // No .slo replaces a source or header, and no two shaders share one.
    sss::JobFiles job_files;
    for (const Compiled& c : compiled)
        for (std::size_t i = 0; i < c.read.size(); ++i)
            job_files.input(c.read[i], (i == 0 ? "the source \"" : "the header \"") +
                                           c.read[i] + "\"" +
                                           (i == 0 ? "" : " included by " + c.file));
    std::vector<std::pair<std::string, const sss::Program*>> writes;
    auto slo_path = [&](const Compiled& c, const sss::Program& p) {
        if (by_source) return std::filesystem::path(c.file).stem().string() + ".slo";
        return output.empty() ? p.name + ".slo" : output;
    };
    for (const Compiled& c : compiled)
        for (const sss::Program& p : c.shaders) {
            const std::string path = slo_path(c, p);
            job_files.output(path, output.empty() ? "\"" + path + "\" (shader " + p.name +
                                                        " of " + c.file + ")"
                                                  : "option -o \"" + path + "\"");
            sss::check_output_target(path);
            writes.emplace_back(path, &p);
        }
    sss::OutputSet outputs;
    for (const auto& [path, program] : writes) {
        const sss::ScopedStage writing("writing " + path);
        sss::write_program_file(*program, path);
    }
    // Printed before the .slo files are committed: a standard output that
    // cannot take it fails the job with the files left as they were.
    if (!quiet)
        for (const Compiled& c : compiled)
            for (const sss::Program& p : c.shaders)
                std::cout << c.file << ": " << sss::shader_kind_name(p.kind) << " "
                          << p.name << " -> " << slo_path(c, p) << "\n";
    sss::flush_standard_output();
    outputs.commit();
    return 0;
}

} // namespace

int main(int argc, char** argv) {
    return sss::run_tool(kTool, argc, argv, run);
}
