// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
/// \file rib_attributes.cpp
/// The reader's attribute requests: colour, sides, orientation, shading,
/// `Attribute`, the surface, displacement and volume shaders (Atmosphere,
/// Interior, Exterior), light sources and the patch bases.

#include "rib_reader.h"

#include <algorithm>

#include "rib_args.h"
#include "sss/util/messages.h"

namespace sss::rib {

namespace {

/// The three numbers of a Color or Opacity request.
glm::dvec3 take_color(const Statement& s) {
    std::size_t i = 0;
    auto n = take_numbers(s, i, 3);
    no_more_args(s, i);
    return {n[0], n[1], n[2]};
}

/// One basis of a Basis request: a name or 16 numbers, then its step.
Basis take_basis(const Statement& s, std::size_t& i, const char* which) {
    need_args(s, i, which);
    Basis b;
    const Value& v = s.args[i];
    if (v.is_string() || (v.is_array() && v.strings.size() == 1)) {
        std::string name = v.is_string() ? v.string : v.strings[0];
        auto nb = named_basis(name);
        if (!nb) fail(s, "unknown basis " + sss::quoted(name));
        b = *nb;
        ++i;
    } else {
        auto n = take_numbers(s, i, 16);
        b.matrix = matrix_from(n);
        b.name = "custom";
    }
    b.step = to_int(s, take_number(s, i), std::string(which) + " step");
    if (b.step < 1) fail(s, std::string(which) + " step must be positive");
    return b;
}

} // namespace

ShaderRef Reader::make_shader(const Statement& s, const std::string& name,
                              ParamList params) {
    ShaderRef ref;
    ref.name = name;
    ref.params = std::move(params);
    ref.shader_to_world = m_ctm;
    ref.source = where(s);
    return ref;
}

void Reader::do_attribute(const Statement& s) {
    std::size_t i = 0;
    std::string group = take_string(s, i, "attribute name");
    ParamList params = take_params(s, i, true);
    ParamList& dst = attrs_mut().groups[group];
    for (Param& p : params.items) dst.set(std::move(p));
}

void Reader::do_color(const Statement& s) {
    attrs_mut().color = take_color(s);
}

void Reader::do_opacity(const Statement& s) {
    attrs_mut().opacity = take_color(s);
}

void Reader::do_sides(const Statement& s) {
    std::size_t i = 0;
    double n = take_number(s, i);
    no_more_args(s, i);
    if (n != 1.0 && n != 2.0) fail(s, "sides must be 1 or 2, got " + fmt(n));
    attrs_mut().sides = static_cast<int>(n);
}

void Reader::do_orientation(const Statement& s) {
    std::size_t i = 0;
    std::string o = take_string(s, i, "orientation");
    no_more_args(s, i);
    bool inside;
    if (o == "outside")
        inside = false;
    else if (o == "inside")
        inside = true;
    else if (o == "lh")
        inside = !current_left_handed();
    else if (o == "rh")
        inside = current_left_handed();
    else
        fail(s, "orientation must be outside, inside, lh or rh, got " + sss::quoted(o));
    attrs_mut().orientation_inside = inside;
}

void Reader::do_reverse_orientation(const Statement& s) {
    no_more_args(s, 0);
    Attributes& a = attrs_mut();
    a.orientation_inside = !a.orientation_inside;
}

void Reader::do_shading_rate(const Statement& s) {
    std::size_t i = 0;
    double r = take_number(s, i);
    no_more_args(s, i);
    if (!(r > 0.0)) fail(s, "shading rate must be positive, got " + fmt(r));
    attrs_mut().shading_rate = r;
}

void Reader::do_shading_interpolation(const Statement& s) {
    std::size_t i = 0;
    std::string mode = take_string(s, i, "interpolation");
    no_more_args(s, i);
    if (mode != "constant" && mode != "smooth")
        fail(s, "interpolation must be constant or smooth, got " + sss::quoted(mode));
    attrs_mut().shading_interpolation = mode;
}

void Reader::do_surface(const Statement& s) {
    std::size_t i = 0;
    std::string name = take_string(s, i, "shader name");
    ParamList params = take_params(s, i, true, true);
    attrs_mut().surface = make_shader(s, name, std::move(params));
}

void Reader::do_coshader(const Statement& s) {
    std::size_t i = 0;
    std::string name = take_string(s, i, "shader name");
    std::string handle = take_handle(s, i);
    ParamList params = take_params(s, i, true, true);
    CoshaderRef ref{handle, make_shader(s, name, std::move(params))};
    auto& list = attrs_mut().coshaders;
    auto it = std::find_if(list.begin(), list.end(),
                           [&](const CoshaderRef& c) { return c.handle == handle; });
    if (it != list.end())
        *it = std::move(ref);
    else
        list.push_back(std::move(ref));
}

void Reader::do_displacement(const Statement& s) {
    std::size_t i = 0;
    std::string name = take_string(s, i, "shader name");
    ParamList params = take_params(s, i, true, true);
    attrs_mut().displacement = make_shader(s, name, std::move(params));
}

void Reader::do_volume_shader(const Statement& s) {
    std::size_t i = 0;
    std::string name = take_string(s, i, "shader name");
    ParamList params = take_params(s, i, true, true);
    std::optional<ShaderRef> ref;
    // RiAtmosphere(RI_NULL) turns the volume off: "null" or "" in a RIB.
    if (!name.empty() && name != "null") ref = make_shader(s, name, std::move(params));
    Attributes& a = attrs_mut();
    if (s.name == "Atmosphere")
        a.atmosphere = std::move(ref);
    else if (s.name == "Interior")
        a.interior = std::move(ref);
    else
        a.exterior = std::move(ref);
}

void Reader::do_light_source(const Statement& s) {
    std::size_t i = 0;
    std::string name = take_string(s, i, "shader name");
    // The handle is there when the rest is not a whole number of pairs.
    std::string handle;
    if ((s.args.size() - i) % 2 == 1)
        handle = take_handle(s, i);
    else
        handle = "unnamed " + std::to_string(m_scene.lights.size());
    ParamList params = take_params(s, i, true, true);
    if (!m_in_world) fail(s, "light sources must be inside WorldBegin/WorldEnd");
    if (m_object) fail(s, "light sources cannot be part of an object definition");
    LightInstance light;
    light.shader = make_shader(s, name, std::move(params));
    light.handle = handle;
    light.area = s.name == "AreaLightSource";
    int index = static_cast<int>(m_scene.lights.size());
    m_scene.lights.push_back(std::move(light));
    m_light_handles[handle] = index;
    set_light(index, true);
}

void Reader::set_light(int index, bool on) {
    auto& on_list = m_attr.attrs.lights_on;
    auto it = std::lower_bound(on_list.begin(), on_list.end(), index);
    bool present = it != on_list.end() && *it == index;
    if (on == present) return;
    auto& list = attrs_mut().lights_on;
    it = std::lower_bound(list.begin(), list.end(), index);
    if (on)
        list.insert(it, index);
    else
        list.erase(it);
}

void Reader::do_illuminate(const Statement& s) {
    std::size_t i = 0;
    std::string handle = take_handle(s, i);
    double on = take_number(s, i);
    no_more_args(s, i);
    auto it = m_light_handles.find(handle);
    if (it == m_light_handles.end())
        fail(s, "unknown light handle " + sss::quoted(handle));
    set_light(it->second, on != 0.0);
}

void Reader::do_basis(const Statement& s) {
    std::size_t i = 0;
    Basis u = take_basis(s, i, "ubasis");
    Basis v = take_basis(s, i, "vbasis");
    no_more_args(s, i);
    Attributes& a = attrs_mut();
    a.u_basis = u;
    a.v_basis = v;
}

} // namespace sss::rib
