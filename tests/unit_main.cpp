// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
// The main of sss_tests. Besides GoogleTest's own flags it takes
//
//   --sss_source=<module>/<file>_test.cpp   run only the tests defined in that file
//   --sss_sources=<a.cpp>,<b.cpp>,...       check that every test is defined in one of
//                                           these files (exit 1 naming the others)
//
// CTest runs one sss_tests process per test file with --sss_source
// (tests/CMakeLists.txt): a process costs about half a second to start (it loads
// every library behind OpenImageIO), so one per test case spent most of the
// suite's time starting processes. The --sss_sources check makes sure that no
// test is lost by that split: a TEST in a header, say, belongs to no file.
#include <gtest/gtest.h>

#include <cstdio>
#include <set>
#include <sstream>
#include <string>
#include <string_view>
#include <vector>

namespace {

bool ends_with_path(std::string_view path, std::string_view suffix) {
    if (path.size() < suffix.size() ||
        path.substr(path.size() - suffix.size()) != suffix) {
        return false;
    }
    return path.size() == suffix.size() || path[path.size() - suffix.size() - 1] == '/';
}

template <typename F>
void for_each_test(F&& f) {
    const auto& unit = *::testing::UnitTest::GetInstance();
    for (int i = 0; i < unit.total_test_suite_count(); ++i) {
        const auto& suite = *unit.GetTestSuite(i);
        for (int j = 0; j < suite.total_test_count(); ++j) {
            f(*suite.GetTestInfo(j));
        }
    }
}

std::vector<std::string> split(const std::string& list, char sep) {
    std::vector<std::string> items;
    std::stringstream stream(list);
    for (std::string item; std::getline(stream, item, sep);) {
        if (!item.empty()) {
            items.push_back(item);
        }
    }
    return items;
}

// The tests defined in `source`, as a GoogleTest filter; empty when there are none.
std::string filter_for_source(const std::string& source) {
    std::string filter;
    for_each_test([&](const ::testing::TestInfo& test) {
        if (ends_with_path(test.file(), source)) {
            filter += (filter.empty() ? "" : ":") + std::string(test.test_suite_name()) +
                      "." + test.name();
        }
    });
    return filter;
}

int check_sources(const std::string& list) {
    const std::vector<std::string> sources = split(list, ',');
    std::set<std::string> strays;
    int count = 0;
    for_each_test([&](const ::testing::TestInfo& test) {
        ++count;
        bool known = false;
        for (const std::string& source : sources) {
            known = known || ends_with_path(test.file(), source);
        }
        if (!known) {
            strays.insert(std::string(test.file()) + ": " + test.test_suite_name() + "." +
                          test.name());
        }
    });
    for (const std::string& stray : strays) {
        std::fprintf(stderr, "sss_tests: test outside the listed test files: %s\n",
                     stray.c_str());
    }
    std::printf("sss_tests: %d tests in %zu files, %zu outside them\n", count,
                sources.size(), strays.size());
    return strays.empty() && count > 0 ? 0 : 1;
}

} // namespace

int main(int argc, char** argv) {
    ::testing::InitGoogleTest(&argc, argv);
    std::string source;
    std::string sources;
    for (int i = 1; i < argc; ++i) {
        const std::string_view arg = argv[i];
        if (arg.rfind("--sss_source=", 0) == 0) {
            source = arg.substr(13);
        } else if (arg.rfind("--sss_sources=", 0) == 0) {
            sources = arg.substr(14);
        } else {
            std::fprintf(stderr, "sss_tests: unknown argument %s\n", argv[i]);
            return 2;
        }
    }
    if (!sources.empty()) {
        return check_sources(sources);
    }
    if (!source.empty()) {
        const std::string filter = filter_for_source(source);
        if (filter.empty()) {
            std::fprintf(stderr, "sss_tests: no test is defined in %s\n", source.c_str());
            return 1;
        }
        if (::testing::GTEST_FLAG(filter) != "*") {
            std::fprintf(stderr,
                         "sss_tests: give --sss_source or --gtest_filter, not both\n");
            return 2;
        }
        ::testing::GTEST_FLAG(filter) = filter;
    }
    return RUN_ALL_TESTS();
}
