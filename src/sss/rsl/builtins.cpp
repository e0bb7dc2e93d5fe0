// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
/// \file builtins.cpp
/// The table of RSL built-in functions (builtins.h): RISpec 3.2 chapter 15
/// and the PRMan extensions production shaders use.

#include "sss/rsl/builtins.h"

#include <algorithm>
#include <array>

namespace sss::detail {

namespace {

constexpr bool V = true; // always varying
constexpr bool D = true; // differentiates

// clang-format off
constexpr BuiltinSignature kTable[] = {
    // --- math (RISpec 15.1)
    {"radians", "f=f"}, {"degrees", "f=f"},
    {"sin", "f=f"}, {"cos", "f=f"}, {"tan", "f=f"},
    {"asin", "f=f"}, {"acos", "f=f"},
    {"atan", "f=f"}, {"atan", "f=ff"},
    {"pow", "f=ff"}, {"pow", "c=cf"}, {"exp", "f=f"}, {"sqrt", "f=f"}, {"inversesqrt", "f=f"},
    {"log", "f=f"}, {"log", "f=ff"},
    {"mod", "f=ff"}, {"abs", "f=f"}, {"abs", "c=c"}, {"abs", "x=x"}, {"sign", "f=f"},
    {"floor", "f=f"}, {"ceil", "f=f"}, {"round", "f=f"},
    {"floor", "c=c"}, {"ceil", "c=c"}, {"round", "c=c"},
    {"floor", "x=x"}, {"ceil", "x=x"}, {"round", "x=x"},
    {"min", "f=ff*"}, {"min", "c=cc*"}, {"min", "x=xx*"},
    {"max", "f=ff*"}, {"max", "c=cc*"}, {"max", "x=xx*"},
    {"clamp", "f=fff"}, {"clamp", "c=ccc"}, {"clamp", "x=xxx"},
    {"mix", "f=fff"}, {"mix", "c=ccf"}, {"mix", "x=xxf"}, {"mix", "c=ccc"},
    {"step", "f=ff"}, {"smoothstep", "f=fff"},
    {"filterstep", "f=ff!", V, D}, {"filterstep", "f=fff!", V, D},
    {"erf", "f=f"}, {"erfc", "f=f"},
    {"spline", "f=ff*"}, {"spline", "c=fc*"}, {"spline", "x=fx*"},
    {"spline", "f=sff*"}, {"spline", "c=sfc*"}, {"spline", "x=sfx*"},
    {"spline", "f=f[f]"}, {"spline", "c=f[c]"}, {"spline", "x=f[x]"},
    {"spline", "f=sf[f]"}, {"spline", "c=sf[c]"}, {"spline", "x=sf[x]"},
    {"random", "f=", V}, {"random", "c=", V}, {"random", "p=", V},
    {"noise", "f=f"}, {"noise", "f=ff"}, {"noise", "f=p"}, {"noise", "f=pf"},
    {"noise", "c=f"}, {"noise", "c=ff"}, {"noise", "c=p"}, {"noise", "c=pf"},
    {"noise", "x=f"}, {"noise", "x=ff"}, {"noise", "x=p"}, {"noise", "x=pf"},
    {"noise", "f=v"}, {"noise", "c=v"}, {"noise", "x=v"},
    {"noise", "f=n"}, {"noise", "c=n"}, {"noise", "x=n"},
    {"pnoise", "f=ff"}, {"pnoise", "f=ffff"}, {"pnoise", "f=pp"}, {"pnoise", "f=pfpf"},
    {"pnoise", "c=ff"}, {"pnoise", "c=ffff"}, {"pnoise", "c=pp"}, {"pnoise", "c=pfpf"},
    {"pnoise", "x=ff"}, {"pnoise", "x=ffff"}, {"pnoise", "x=pp"}, {"pnoise", "x=pfpf"},
    {"cellnoise", "f=f"}, {"cellnoise", "f=ff"}, {"cellnoise", "f=p"}, {"cellnoise", "f=pf"},
    {"cellnoise", "c=f"}, {"cellnoise", "c=ff"}, {"cellnoise", "c=p"}, {"cellnoise", "c=pf"},
    {"cellnoise", "x=f"}, {"cellnoise", "x=ff"}, {"cellnoise", "x=p"}, {"cellnoise", "x=pf"},

    // --- geometry (RISpec 15.2)
    {"xcomp", "f=x"}, {"ycomp", "f=x"}, {"zcomp", "f=x"},
    {"setxcomp", "o=Xf"}, {"setycomp", "o=Xf"}, {"setzcomp", "o=Xf"},
    {"length", "f=x"}, {"normalize", "v=v"}, {"normalize", "n=n"}, {"normalize", "v=p"},
    {"distance", "f=pp"}, {"ptlined", "f=ppp"},
    {"rotate", "x=xfpp"},
    {"area", "f=p", V, D}, {"area", "f=ps", V, D},
    {"faceforward", "x=xv"}, {"faceforward", "x=xvx"},
    {"reflect", "v=vx"}, {"refract", "v=vxf"},
    {"fresnel", "o=vxfFF"}, {"fresnel", "o=vxfFFVV"},
    {"transform", "p=sp"}, {"transform", "p=ssp"}, {"transform", "p=mp"}, {"transform", "p=smp"},
    {"vtransform", "v=sv"}, {"vtransform", "v=ssv"}, {"vtransform", "v=mv"}, {"vtransform", "v=smv"},
    {"ntransform", "n=sn"}, {"ntransform", "n=ssn"}, {"ntransform", "n=mn"}, {"ntransform", "n=smn"},
    {"depth", "f=p"},
    {"calculatenormal", "n=p", V, D},
    {"Du", "f=f", V, D}, {"Du", "c=c", V, D}, {"Du", "v=x", V, D},
    {"Dv", "f=f", V, D}, {"Dv", "c=c", V, D}, {"Dv", "v=x", V, D},
    {"Deriv", "f=ff", V, D}, {"Deriv", "c=cf", V, D}, {"Deriv", "v=xf", V, D},

    // --- colour and matrix (RISpec 15.3, 15.4)
    {"comp", "f=cf"}, {"comp", "f=xf"}, {"setcomp", "o=Cff"}, {"setcomp", "o=Xff"},
    {"comp", "f=mff"}, {"setcomp", "o=Mfff"},
    {"ctransform", "c=sc"}, {"ctransform", "c=ssc"},
    {"determinant", "f=m"}, {"translate", "m=mv"}, {"rotate", "m=mfv"}, {"scale", "m=mp"},

    // --- strings (RISpec 15.8, PRMan)
    {"concat", "s=ss*"}, {"format", "s=s.*"}, {"printf", "o=s.*"}, {"match", "f=ss"},

    // --- local illumination (RISpec 15.5)
    {"ambient", "c=", V},
    {"diffuse", "c=n", V}, {"diffuse", "c=v", V},
    {"specular", "c=nvf", V}, {"specular", "c=vvf", V},
    {"specularbrdf", "c=vnvf"}, {"specularbrdf", "c=vvvf"},
    {"phong", "c=nvf", V}, {"phong", "c=vvf", V},

    // --- texture maps (RISpec 15.6); the second argument is the channel
    {"texture", "f=sf!", V, D}, {"texture", "c=sf!", V, D},
    {"texture", "f=sfff!", V, D}, {"texture", "c=sfff!", V, D},
    {"texture", "f=sfffffffff!", V}, {"texture", "c=sfffffffff!", V},
    {"environment", "f=sfv!", V, D}, {"environment", "c=sfv!", V, D},
    {"shadow", "f=sfp!", V}, {"shadow", "c=sfp!", V},
    {"shadow", "f=sfpppp!", V}, {"shadow", "c=sfpppp!", V},
    {"textureinfo", "f=ssF"}, {"textureinfo", "f=ss[F]"}, {"textureinfo", "f=ssS"},
    {"textureinfo", "f=ssM"},

    // --- 3-D textures (PRMan 13+)
    {"texture3d", "f=spn@", V}, {"bake3d", "f=sspn!", V},

    // --- ray tracing (PRMan 11+)
    {"transmission", "c=pp!", V}, {"trace", "c=pv!", V},
    {"occlusion", "f=pnf!", V}, {"indirectdiffuse", "c=pnf!", V},

    // --- queries and message passing
    {"attribute", "f=sF"}, {"attribute", "f=sC"}, {"attribute", "f=sP"}, {"attribute", "f=sV"},
    {"attribute", "f=sN"}, {"attribute", "f=sM"}, {"attribute", "f=sS"}, {"attribute", "f=s[F]"},
    {"option", "f=sF"}, {"option", "f=sC"}, {"option", "f=sP"}, {"option", "f=sS"},
    {"option", "f=s[F]"}, {"option", "f=sM"},
    {"rendererinfo", "f=sF"}, {"rendererinfo", "f=sS"}, {"rendererinfo", "f=s[F]"},
    {"raylevel", "f="}, {"rayinfo", "f=sF"}, {"rayinfo", "f=sS"}, {"rayinfo", "f=sP"}, {"rayinfo", "f=sV"},
    // (message passing: the values differ per point, the other shader's)
    {"surface", "f=sF", V}, {"surface", "f=sC", V}, {"surface", "f=sP", V},
    {"surface", "f=sV", V}, {"surface", "f=sN", V}, {"surface", "f=sS", V},
    {"surface", "f=sM", V},
    {"displacement", "f=sF", V}, {"displacement", "f=sC", V}, {"displacement", "f=sP", V},
    {"displacement", "f=sV", V}, {"displacement", "f=sN", V}, {"displacement", "f=sS", V},
    {"displacement", "f=sM", V},
    {"lightsource", "f=sF", V}, {"lightsource", "f=sC", V}, {"lightsource", "f=sP", V},
    {"lightsource", "f=sV", V}, {"lightsource", "f=sN", V}, {"lightsource", "f=sS", V},
    {"lightsource", "f=sM", V},
    {"atmosphere", "f=sF", V}, {"atmosphere", "f=sC", V}, {"atmosphere", "f=sP", V},
    {"atmosphere", "f=sV", V}, {"atmosphere", "f=sN", V}, {"atmosphere", "f=sS", V},
    {"atmosphere", "f=sM", V},
};
// clang-format on

} // namespace

std::span<const BuiltinSignature> builtin_signatures() {
    return kTable;
}

bool is_builtin(std::string_view name) {
    return std::any_of(std::begin(kTable), std::end(kTable),
                       [&](const BuiltinSignature& s) { return name == s.name; });
}

ShadingType letter_type(char c, ShadingType x) {
    switch (c) {
    case 'f':
        return ShadingType::Float;
    case 'c':
        return ShadingType::Color;
    case 'p':
        return ShadingType::Point;
    case 'v':
        return ShadingType::Vector;
    case 'n':
        return ShadingType::Normal;
    case 'm':
        return ShadingType::Matrix;
    case 's':
        return ShadingType::String;
    case 'x':
        return x;
    default:
        return ShadingType::Void;
    }
}

} // namespace sss::detail
