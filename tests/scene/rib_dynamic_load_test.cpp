// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
/// \file rib_dynamic_load_test.cpp
/// Tests of Procedural "DynamicLoad" (rib_dynamic_load.cpp) and the Ri C
/// binding (ri_api.cpp, ri_geometry.cpp) with a DSO written in C
/// (procedural_dso.c): the primitives its Ri calls make, their parameter
/// lengths from the declarations and the topology, procedurals of its own
/// run to their depth, the standard procedurals it names, its data always
/// freed, and the errors that name the DSO, the call and the cause.
///
/// Suite names all start with "RibDynamicLoad".

#include <dlfcn.h>
#include <gtest/gtest.h>

#include <fstream>
#include <string>

#include <glm/vec4.hpp>

#include "sss/scene/rib.h"
#include "sss/scene/scene.h"
#include "test_util.h"

namespace {

const std::string kDso = SSS_TEST_PROCEDURAL;

std::string procedural(const std::string& data) {
    return "Procedural \"DynamicLoad\" [\"" + kDso + "\" \"" + data +
           "\"] [-1 1 -1 1 -1 1]\n";
}

sss::Scene scene_of(const std::string& world) {
    return sss::parse_rib("Format 64 64 1\nProjection \"perspective\"\nWorldBegin\n" +
                              world + "WorldEnd\n",
                          "d.rib");
}

std::string error_of(const std::string& world) {
    try {
        scene_of(world);
    } catch (const std::exception& e) {
        return e.what();
    }
    return "";
}

/// The DSO kept loaded by the test, to read its count of live data blocks
/// after the reader closed its own handle.
class DsoCounter {
public:
    DsoCounter() : m_handle(dlopen(kDso.c_str(), RTLD_NOW | RTLD_LOCAL)) {}
    ~DsoCounter() {
        if (m_handle) dlclose(m_handle);
    }
    int live() const {
        auto f = reinterpret_cast<int (*)()>(dlsym(m_handle, "sss_test_live_blocks"));
        return f ? f() : -1;
    }
    bool loaded() const { return m_handle != nullptr; }

private:
    void* m_handle;
};

std::size_t count(const sss::Scene& s, sss::PrimitiveKind kind) {
    std::size_t n = 0;
    for (const sss::Primitive& p : s.primitives) n += p.kind == kind;
    return n;
}

} // namespace

TEST(RibDynamicLoad, MeshCallsMakeTheirPrimitivesWithParameters) {
    const sss::Scene s = scene_of("Translate 0 0 5\n" + procedural("mesh"));
    ASSERT_EQ(count(s, sss::PrimitiveKind::PointsPolygons), 1u);
    ASSERT_EQ(count(s, sss::PrimitiveKind::Curves), 1u);
    ASSERT_EQ(count(s, sss::PrimitiveKind::Patch), 1u);
    for (const sss::Primitive& p : s.primitives) {
        // The procedural's transform applies to what it makes.
        EXPECT_NEAR((p.object_to_world * glm::dvec4(0, 0, 0, 1)).z, 5.0, 1e-12);
        if (p.kind == sss::PrimitiveKind::PointsPolygons) {
            ASSERT_TRUE(p.params.has("Cs"));
            EXPECT_EQ(p.params.find("Cs")->numbers.size(), 12u);
            EXPECT_EQ(p.params.find("Cs")->numbers[4], 1.0);
            // Inline declaration: uniform, one face.
            ASSERT_TRUE(p.params.has("weight"));
            EXPECT_EQ(p.params.find("weight")->numbers.size(), 1u);
            // RiDeclare'd varying: one per vertex.
            ASSERT_TRUE(p.params.has("Kfoo"));
            EXPECT_EQ(p.params.find("Kfoo")->numbers.size(), 4u);
            ASSERT_TRUE(p.attributes->surface.has_value());
            EXPECT_EQ(p.attributes->surface->name, "matte");
        }
        if (p.kind == sss::PrimitiveKind::Curves) {
            // b-spline step 1: 4 and 7 vertices are 1 and 4 segments, 2 + 5
            // varying widths.
            ASSERT_TRUE(p.params.has("width"));
            EXPECT_EQ(p.params.find("width")->numbers.size(), 7u);
            EXPECT_EQ(p.params.find("P")->numbers.size(), 33u);
        }
    }
}

TEST(RibDynamicLoad, ProceduralsOfItsOwnRunToTheirDepthAndAreFreed) {
    DsoCounter counter;
    ASSERT_TRUE(counter.loaded()) << dlerror();
    const sss::Scene s = scene_of(procedural("tree 3"));
    EXPECT_EQ(count(s, sss::PrimitiveKind::Sphere), 15u);
    EXPECT_EQ(counter.live(), 0);
    // Each level is half the size of the one above, 1.5 to the side.
    double smallest = 1e9;
    for (const sss::Primitive& p : s.primitives)
        smallest = std::min(smallest, glm::length(glm::dvec3(p.object_to_world[0])));
    EXPECT_NEAR(smallest, 0.125, 1e-12);
}

TEST(RibDynamicLoad, StandardProceduralsItNamesAreRead) {
    sss::test::TempDir dir;
    const std::string archive = dir.file("a.rib");
    std::ofstream(archive) << "Sphere 1 -1 1 360\nDisk 0 1 360\n";
    DsoCounter counter;
    const sss::Scene s = scene_of(procedural("archive " + archive));
    EXPECT_EQ(count(s, sss::PrimitiveKind::Sphere), 1u);
    EXPECT_EQ(count(s, sss::PrimitiveKind::Disk), 1u);
    EXPECT_EQ(counter.live(), 0);
    // A DSO that loads another (here itself) through RiProcDynamicLoad.
    const sss::Scene t = scene_of(procedural("load " + kDso + " tree"));
    EXPECT_EQ(count(t, sss::PrimitiveKind::Sphere), 1u);
}

TEST(RibDynamicLoad, ErrorsNameTheDsoTheCallAndTheCause) {
    DsoCounter counter;
    const std::string undeclared = error_of(procedural("undeclared"));
    EXPECT_NE(undeclared.find("testproc.so (DynamicLoad at d.rib:4)"), std::string::npos)
        << undeclared;
    EXPECT_NE(undeclared.find("Sphere"), std::string::npos) << undeclared;
    EXPECT_NE(undeclared.find("\"notdeclared\" is not declared"), std::string::npos)
        << undeclared;
    EXPECT_NE(error_of(procedural("unbalanced")).find("left 1 block(s) open"),
              std::string::npos);
    EXPECT_NE(error_of(procedural("early")).find("not in ConvertParameters"),
              std::string::npos);
    // Whatever failed, the data was freed.
    EXPECT_EQ(counter.live(), 0);
    const std::string missing =
        error_of("Procedural \"DynamicLoad\" [\"no_such_dso\" \"\"] [-1 1 -1 1 -1 1]\n");
    EXPECT_NE(missing.find("no_such_dso"), std::string::npos) << missing;
    // A shared object that is not a procedural.
    const std::string libz = "/lib/x86_64-linux-gnu/libz.so.1";
    if (std::ifstream(libz)) {
        const std::string not_one = error_of("Procedural \"DynamicLoad\" [\"" + libz +
                                             "\" \"\"] [-1 1 -1 1 -1 1]\n");
        EXPECT_NE(not_one.find("does not export ConvertParameters"), std::string::npos)
            << not_one;
    }
}
