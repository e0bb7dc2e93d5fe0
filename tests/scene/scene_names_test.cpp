// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
/// \file scene_names_test.cpp
/// Tests of the scene layer's name tables (sss/scene/scene.h): the RIB
/// spellings of parameter types, storage classes and primitive kinds.

#include <gtest/gtest.h>

#include <string>

#include "sss/scene/scene.h"

namespace {

using sss::ParamClass;
using sss::ParamType;
using sss::PrimitiveKind;

TEST(SceneNames, ParamTypesRoundTrip) {
    const std::pair<ParamType, const char*> types[] = {
        {ParamType::Float, "float"},   {ParamType::Integer, "integer"},
        {ParamType::String, "string"}, {ParamType::Color, "color"},
        {ParamType::Point, "point"},   {ParamType::Vector, "vector"},
        {ParamType::Normal, "normal"}, {ParamType::HPoint, "hpoint"},
        {ParamType::Matrix, "matrix"},
    };
    for (const auto& [type, name] : types) {
        EXPECT_STREQ(sss::param_type_name(type), name);
        EXPECT_EQ(sss::parse_param_type(name), type) << name;
    }
    // "int" is read as integer but never written.
    EXPECT_EQ(sss::parse_param_type("int"), ParamType::Integer);
    EXPECT_FALSE(sss::parse_param_type("Float"));
    EXPECT_FALSE(sss::parse_param_type(""));
    EXPECT_FALSE(sss::parse_param_type("uniform"));
}

TEST(SceneNames, ParamClassesRoundTrip) {
    const std::pair<ParamClass, const char*> classes[] = {
        {ParamClass::Constant, "constant"},       {ParamClass::Uniform, "uniform"},
        {ParamClass::Varying, "varying"},         {ParamClass::Vertex, "vertex"},
        {ParamClass::FaceVarying, "facevarying"}, {ParamClass::FaceVertex, "facevertex"},
    };
    for (const auto& [storage, name] : classes) {
        EXPECT_STREQ(sss::param_class_name(storage), name);
        EXPECT_EQ(sss::parse_param_class(name), storage) << name;
    }
    EXPECT_FALSE(sss::parse_param_class("float"));
    EXPECT_FALSE(sss::parse_param_class("Vertex"));
}

TEST(SceneNames, PrimitiveKinds) {
    EXPECT_STREQ(sss::primitive_kind_name(PrimitiveKind::Polygon), "Polygon");
    EXPECT_STREQ(sss::primitive_kind_name(PrimitiveKind::PointsGeneralPolygons),
                 "PointsGeneralPolygons");
    EXPECT_STREQ(sss::primitive_kind_name(PrimitiveKind::SubdivisionMesh),
                 "SubdivisionMesh");
    EXPECT_STREQ(sss::primitive_kind_name(PrimitiveKind::Hyperboloid), "Hyperboloid");
    EXPECT_STREQ(sss::primitive_kind_name(PrimitiveKind::PatchMesh), "PatchMesh");
    EXPECT_STREQ(sss::primitive_kind_name(PrimitiveKind::Teapot), "Teapot");
}

TEST(SceneNames, ClassCountsOf) {
    const sss::ClassCounts counts{2, 3, 5, 7, 11};
    EXPECT_EQ(counts.of(ParamClass::Constant), 1u);
    EXPECT_EQ(counts.of(ParamClass::Uniform), 2u);
    EXPECT_EQ(counts.of(ParamClass::Varying), 3u);
    EXPECT_EQ(counts.of(ParamClass::Vertex), 5u);
    EXPECT_EQ(counts.of(ParamClass::FaceVarying), 7u);
    EXPECT_EQ(counts.of(ParamClass::FaceVertex), 11u);
}

} // namespace
