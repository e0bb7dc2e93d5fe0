// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
/// \file did_you_mean_test.cpp
/// The hints of command-line errors: an unknown option gets the closest
/// option its tool's usage text lists, an unknown material the closest preset.

#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "sss/cli/tool.h"
#include "sss/diffusion/material.h"
#include "sss/diffusion/ssdiffusion.h"
#include "sss/util/error.h"

namespace {

const char* const kUsage = R"(usage: mytool [options] in.ptc out.ptc
       mytool -merge [-newer 1] p1.ptpart out.ptc
       (also: -filter ssdiffusion)

Does things to clouds (x86-64 kernels; values in [-1, 1]).

options:
  -material NAME         apple, marble (default marble)
  -p:N, -t:N             the same as -threads N
  -threads N             0 = all usable cores, <0 = all but N
  -compress 0|1, -ptcversion 0|1|2   .ptc output options
  -axis x|y|z|-x         the side
  --dry-run              nothing-written-
  -h, --help             this help
  --version              version information
)";

std::string message(const std::string& opt) {
    return sss::unknown_option(opt, kUsage).what();
}

TEST(DidYouMean, UsageOptionsAreTheListedOptions) {
    const std::vector<std::string> expected = {
        "-merge",    "-newer",      "-filter", "-material", "-p", "-t",     "-threads",
        "-compress", "-ptcversion", "-axis",   "--dry-run", "-h", "--help", "--version"};
    EXPECT_EQ(sss::usage_options(kUsage), expected);
}

TEST(DidYouMean, UnknownOptionGetsTheClosest) {
    EXPECT_EQ(message("materail"), "unknown option -materail; did you mean -material?");
    EXPECT_EQ(message("thread"), "unknown option -thread; did you mean -threads?");
    EXPECT_EQ(message("Newer"), "unknown option -Newer; did you mean -newer?");
    EXPECT_EQ(message("verison"), "unknown option -verison; did you mean --version?");
    EXPECT_EQ(message("ptcverison"),
              "unknown option -ptcverison; did you mean -ptcversion?");
    EXPECT_EQ(message("dryrun"), "unknown option -dryrun; did you mean --dry-run?");
}

TEST(DidYouMean, NothingCloseNothingSuggested) {
    EXPECT_EQ(message("bogus"), "unknown option -bogus");
    EXPECT_EQ(message("q"), "unknown option -q");
    EXPECT_EQ(message("x"), "unknown option -x");
    EXPECT_EQ(message("spacing"), "unknown option -spacing");
    // A listed option refused where it stands is not suggested to itself.
    EXPECT_EQ(message("axis"), "unknown option -axis");
    EXPECT_EQ(sss::unknown_option("materail", "").what(),
              std::string("unknown option -materail"));
}

TEST(DidYouMean, UnknownMaterialGetsTheClosestPreset) {
    EXPECT_EQ(sss::unknown_material_message("skin11"),
              "unknown material 'skin11'; did you mean 'skin1'?");
    EXPECT_EQ(sss::unknown_material_message("Marble"),
              "unknown material 'Marble'; did you mean 'marble'?");
    EXPECT_EQ(sss::unknown_material_message("wholmilk"),
              "unknown material 'wholmilk'; did you mean 'wholemilk'?");
    EXPECT_EQ(sss::unknown_material_message("granite"),
              "unknown material 'granite' (known: " + sss::material_names() + ")");
}

TEST(DidYouMean, MaterialOptionAndValidateUseTheHint) {
    sss::SsDiffusionOptions options;
    sss::ArgScanner args({"skin11"});
    try {
        sss::ssdiffusion_option(args, "material", options);
        FAIL() << "skin11 accepted";
    } catch (const sss::UsageError& e) {
        EXPECT_EQ(std::string(e.what()),
                  "option -material: unknown material 'skin11'; did you mean 'skin1'?");
    }
    sss::MaterialSpec spec;
    spec.preset = "aple";
    try {
        spec.validate();
        FAIL() << "aple accepted";
    } catch (const sss::UsageError& e) {
        EXPECT_EQ(std::string(e.what()),
                  "unknown material 'aple'; did you mean 'apple'?");
    }
}

} // namespace
