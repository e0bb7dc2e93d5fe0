// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
/// \file rib_subdiv_tags_test.cpp
/// Tests of subdivision mesh tags in the RIB (rib_subdiv_tags.cpp): the tags
/// the dicer carries out are kept, the face-varying ones accepted, others an
/// error (read leniently: left out with a warning), and
/// HierarchicalSubdivisionMesh read as a SubdivisionMesh with its string
/// arguments, its edits not implemented.
///
/// Suite names all start with "RibSubdivTags".

#include <gtest/gtest.h>

#include <string>

#include "sss/scene/rib.h"
#include "sss/scene/scene.h"
#include "sss/util/error.h"

namespace {

const std::string kCage =
    "[4 4 4 4 4 4] [0 1 3 2 2 3 5 4 4 5 7 6 6 7 1 0 1 7 5 3 6 0 2 4] ";
const std::string kP =
    " \"P\" [-1 -1 1 1 -1 1 -1 1 1 1 1 1 -1 1 -1 1 1 -1 -1 -1 -1 1 -1 -1]";

sss::Scene read(const std::string& mesh, bool lenient = false) {
    sss::RibReadOptions o;
    o.lenient = lenient;
    return sss::parse_rib("WorldBegin\n" + mesh + "\nWorldEnd\n", "t.rib", o);
}

std::string error_of(const std::string& mesh) {
    try {
        read(mesh);
    } catch (const std::exception& e) {
        return e.what();
    }
    return "";
}

} // namespace

TEST(RibSubdivTags, KnownTagsAreKeptAndFaceVaryingOnesAccepted) {
    const sss::Scene s =
        read("SubdivisionMesh \"catmull-clark\" " + kCage +
             "[\"interpolateboundary\" \"facevaryinginterpolateboundary\" "
             "\"crease\" \"hole\"] [1 0 1 0 2 1 1 0] [1 2 0 1 5] [2.5]" +
             kP);
    ASSERT_EQ(s.primitives.size(), 1u);
    const sss::Primitive& p = s.primitives[0];
    EXPECT_EQ(p.tags, (std::vector<std::string>{"interpolateboundary",
                                                "facevaryinginterpolateboundary",
                                                "crease", "hole"}));
    EXPECT_EQ(p.tag_intargs, (std::vector<int>{1, 2, 0, 1, 5}));
    EXPECT_TRUE(s.warnings.empty());
}

TEST(RibSubdivTags, OtherTagsAreAnErrorOrLeftOutLeniently) {
    const std::string mesh = "SubdivisionMesh \"catmull-clark\" " + kCage +
                             "[\"stitch\" \"corner\"] [2 1 1 1] [0 1 3] [0.5 2]" + kP;
    EXPECT_NE(error_of(mesh).find("t.rib:2: SubdivisionMesh: subdivision tag \"stitch\" "
                                  "is not supported"),
              std::string::npos)
        << error_of(mesh);
    const sss::Scene s = read(mesh, true);
    const sss::Primitive& p = s.primitives.at(0);
    EXPECT_EQ(p.tags, (std::vector<std::string>{"corner"}));
    EXPECT_EQ(p.tag_nargs, (std::vector<int>{1, 1}));
    EXPECT_EQ(p.tag_intargs, (std::vector<int>{3}));
    EXPECT_EQ(p.tag_floatargs, (std::vector<double>{2.0}));
    EXPECT_EQ(s.warnings.size(), 1u);
}

TEST(RibSubdivTags, HierarchicalMeshReadsAsASubdivisionMesh) {
    const sss::Scene s =
        read("HierarchicalSubdivisionMesh \"catmull-clark\" " + kCage +
             "[\"crease\" \"creasemethod\"] [2 1 0 0 0 1] [0 1] [3] [\"normal\"]" + kP);
    ASSERT_EQ(s.primitives.size(), 1u);
    const sss::Primitive& p = s.primitives[0];
    EXPECT_EQ(p.kind, sss::PrimitiveKind::SubdivisionMesh);
    EXPECT_EQ(p.tags, (std::vector<std::string>{"crease"}));
    EXPECT_EQ(p.tag_nargs, (std::vector<int>{2, 1}));
    EXPECT_TRUE(s.warnings.empty());
    // Chaikin creases and hierarchical edits are not implemented.
    EXPECT_NE(error_of("HierarchicalSubdivisionMesh \"catmull-clark\" " + kCage +
                       "[\"creasemethod\"] [0 0 1] [] [] [\"chaikin\"]" + kP)
                  .find("creasemethod \"chaikin\" is not supported"),
              std::string::npos);
    EXPECT_NE(error_of("HierarchicalSubdivisionMesh \"catmull-clark\" " + kCage +
                       "[\"vertexedit\"] [2 3 2] [1 0] [0 0 1] [\"add\" \"P\"]" + kP)
                  .find("hierarchical edits (\"vertexedit\") are not supported"),
              std::string::npos);
    EXPECT_NE(error_of("HierarchicalSubdivisionMesh \"catmull-clark\" " + kCage +
                       "[\"crease\"] [2 1] [0 1] [3] []" + kP)
                  .find("nargs must have 3 numbers per tag"),
              std::string::npos);
}
