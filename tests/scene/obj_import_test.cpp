// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
/// \file obj_import_test.cpp
/// Tests of the Wavefront OBJ import through its own interface
/// (src/sss/scene/obj_import.h); rib_test.cpp covers it through ReadArchive.

#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "../../src/sss/scene/obj_import.h"
#include "sss/scene/rib.h"

namespace {

using sss::detail::import_obj;

TEST(ObjImport, FacesPositionsAndNormals) {
    std::vector<std::string> warnings;
    auto mesh = import_obj("# a quad and a triangle\n"
                           "v 0 0 0\nv 1 0 0\nv 1 1 0 1.0\nv 0 1 0\n"
                           "vn 0 0 1\nvt 0 0\n"
                           "f 1//1 2//1 3//1 4//1\n"
                           "v 2 0 0 0.5 0.5 0.5\n"
                           "f -3/1/-1 -2/1/1 -1//1\n",
                           "m.obj", warnings);
    ASSERT_TRUE(mesh);
    EXPECT_TRUE(warnings.empty());
    EXPECT_EQ(mesh->first_face_line, 8);
    const sss::Primitive& p = mesh->primitive;
    EXPECT_EQ(p.kind, sss::PrimitiveKind::PointsPolygons);
    EXPECT_EQ(p.nverts, (std::vector<int>{4, 3}));
    EXPECT_EQ(p.verts, (std::vector<int>{0, 1, 2, 3, 2, 3, 4}));
    const sss::Param* P = p.params.find("P");
    ASSERT_TRUE(P);
    EXPECT_EQ(P->storage, sss::ParamClass::Vertex);
    EXPECT_EQ(P->numbers,
              (std::vector<double>{0, 0, 0, 1, 0, 0, 1, 1, 0, 0, 1, 0, 2, 0, 0}));
    const sss::Param* N = p.params.find("N");
    ASSERT_TRUE(N);
    EXPECT_EQ(N->storage, sss::ParamClass::FaceVarying);
    EXPECT_EQ(N->element_count(), 7u);
    EXPECT_FALSE(p.attributes);
    EXPECT_TRUE(p.source.empty());
}

TEST(ObjImport, UnusedVerticesDroppedAndNormalsOnlyWhenEveryCornerHasOne) {
    std::vector<std::string> warnings;
    auto mesh = import_obj("v 0 0 0\nv 1 0 0\nv 1 1 0\nv 5 5 5\nvn 0 0 1\n"
                           "f 1//1 2//1 3//1\nf 1 3 2\n",
                           "a.obj", warnings);
    ASSERT_TRUE(mesh);
    EXPECT_FALSE(mesh->primitive.params.has("N"));
    EXPECT_EQ(mesh->primitive.params.find("P")->element_count(), 3u);
    EXPECT_EQ(mesh->first_face_line, 6);
}

TEST(ObjImport, ContinuationsCarriageReturnsAndComments) {
    std::vector<std::string> warnings;
    auto mesh = import_obj("v 0 0 0\r\nv 1 0 \\\n 0\nv 0 1 0 # third\n\nf 1 \\\n2 \\\n3\n"
                           "bogus\n",
                           "c.obj", warnings);
    ASSERT_TRUE(mesh);
    EXPECT_EQ(mesh->primitive.nverts, (std::vector<int>{3}));
    EXPECT_EQ(mesh->first_face_line, 6);
    // Lines after continuations keep their own numbers.
    ASSERT_EQ(warnings.size(), 1u);
    EXPECT_EQ(warnings[0], "c.obj:9: unsupported OBJ statement 'bogus', skipped");
}

TEST(ObjImport, UnsupportedStatementsWarnOnceAndGroupingIsSilent) {
    std::vector<std::string> warnings{"earlier"};
    auto mesh = import_obj("mtllib x.mtl\no a\ng b\ns off\nusemtl red\nl 1 2\n"
                           "v 0 0 0\nv 1 0 0\nv 0 1 0\ncstype bspline\ncstype bezier\n"
                           "f 1 2 3\n",
                           "w.obj", warnings);
    ASSERT_TRUE(mesh);
    EXPECT_EQ(warnings,
              (std::vector<std::string>{
                  "earlier", "w.obj:10: unsupported OBJ statement 'cstype', skipped"}));
}

TEST(ObjImport, RepeatedCornersAndOutlinesAreDroppedDegenerateFacesLeftOut) {
    std::vector<std::string> warnings;
    // A square walked 2000 times in one face, a triangle with a corner
    // repeated (and its last corner on its first), and a face of two
    // distinct corners.
    std::string square = "f";
    for (int k = 0; k < 2000; ++k) square += " 1//1 2//1 3//1 4//1";
    auto mesh = import_obj("v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nvn 0 0 1\n" + square +
                               "\nf 1//1 2//1 2//1 3//1 1//1\nf 1//1 2//1 1//1 2//1\n",
                           "r.obj", warnings);
    ASSERT_TRUE(mesh);
    const sss::Primitive& p = mesh->primitive;
    EXPECT_EQ(p.nverts, (std::vector<int>{4, 3}));
    EXPECT_EQ(p.verts, (std::vector<int>{0, 1, 2, 3, 0, 1, 2}));
    EXPECT_EQ(p.params.find("N")->element_count(), 7u);
    EXPECT_EQ(warnings,
              (std::vector<std::string>{
                  "r.obj: 1 face with fewer than 3 distinct corners left out"}));
    // A face that only looks periodic is kept whole.
    warnings.clear();
    auto kept = import_obj("v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1 2 3 1 2 4\n", "k.obj",
                           warnings);
    ASSERT_TRUE(kept);
    EXPECT_EQ(kept->primitive.nverts, (std::vector<int>{6}));
    EXPECT_TRUE(warnings.empty());
}

TEST(ObjImport, NoFaces) {
    std::vector<std::string> warnings;
    EXPECT_FALSE(import_obj("v 0 0 0\n", "e.obj", warnings));
    EXPECT_EQ(warnings, (std::vector<std::string>{"e.obj: no faces, nothing imported"}));
    warnings.clear();
    EXPECT_FALSE(import_obj("", "empty.obj", warnings));
    EXPECT_EQ(warnings.size(), 1u);
}

TEST(ObjImport, Errors) {
    struct Case {
        const char* text;
        int line;
        const char* keyword;
        const char* message;
    };
    const Case cases[] = {
        {"v 0 0 0\nv 1 0 0\nv 1 1 0\n\nf 1 2 4\n", 5, "f",
         "bad.obj:5: f: vertex index 4 out of range (3 defined)"},
        {"v 0 0 0\nv 1 0 0\nv 1 1 0\nf 0 1 2\n", 4, "f",
         "bad.obj:4: f: vertex index 0 (OBJ counts from 1)"},
        {"v 0 nan 0\n", 1, "v", "bad.obj:1: v: not a finite number: 'nan'"},
        {"v 0 0\n", 1, "v",
         "bad.obj:1: v: expected x y z [w] (or x y z r g b), got 2 numbers"},
        {"vn 0 0\n", 1, "vn", "bad.obj:1: vn: expected 3 numbers, got 2"},
        {"v 0 0 0\nf 1 1\n", 2, "f",
         "bad.obj:2: f: a face needs at least 3 vertices, got 2"},
        {"v 0 0 0\nf 1 1 x\n", 2, "f", "bad.obj:2: f: malformed vertex index 'x'"},
        {"v 0 0 0\nf 1/1 1 1\n", 2, "f",
         "bad.obj:2: f: texture index 1 out of range (0 defined)"},
        {"v 0 0 0\nf 1//-1 1 1\n", 2, "f",
         "bad.obj:2: f: normal index -1 out of range (0 defined)"},
    };
    for (const Case& c : cases) {
        std::vector<std::string> warnings;
        try {
            import_obj(c.text, "bad.obj", warnings);
            ADD_FAILURE() << c.text << ": no error";
        } catch (const sss::RibError& e) {
            EXPECT_EQ(e.line(), c.line) << c.text;
            EXPECT_EQ(e.statement(), c.keyword) << c.text;
            EXPECT_EQ(e.path(), "bad.obj");
            EXPECT_EQ(std::string(e.what()), c.message);
        }
    }
}

} // namespace
