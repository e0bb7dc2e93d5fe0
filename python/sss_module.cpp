// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
/// \file sss_module.cpp
/// sss._sss: the Python binding of the sss library (docs/python.md). A front
/// end like the cli: it turns Python values into the library's structs (and
/// the keyword options into the words the cli's option parsers read, so that
/// the values are checked where the tools check them) and the results back
/// into numpy arrays. The pure-Python package (python/sss/__init__.py) wraps
/// these functions with keyword arguments, the Cloud dict and warnings.

#include <pybind11/functional.h>
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <cstring>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "sss/brick/brickmap.h"
#include "sss/brick/brickmap_tools.h"
#include "sss/cli/args.h"
#include "sss/cli/job.h"
#include "sss/cli/options.h"
#include "sss/cloud/cloud_texture3d.h"
#include "sss/cloud/point_cloud.h"
#include "sss/cloud/point_cloud_io.h"
#include "sss/diffusion/filter_job.h"
#include "sss/diffusion/ssdiffusion.h"
#include "sss/util/atomic_output.h"
#include "sss/util/error.h"
#include "sss/util/frame_pattern.h"
#include "sss/util/isa.h"
#include "sss/util/job_files.h"
#include "sss/util/limits.h"
#include "sss/util/parse.h"
#include "sss/util/progress.h"
#include "sss/util/threads.h"
#include "sss/util/version.h"

namespace py = pybind11;

namespace {

// ---------------------------------------------------------------------------
// Exceptions: sss.Error and its subclasses (python/sss/_errors.py), which
// also derive from the builtin a Python caller would catch (OSError,
// FileNotFoundError, ValueError, MemoryError).
// ---------------------------------------------------------------------------

/// The classes, looked up once when the module is imported (references kept
/// for the interpreter's life: never released at exit).
struct ErrorTypes {
    PyObject* error = nullptr;
    PyObject* usage = nullptr;
    PyObject* format = nullptr;
    PyObject* value = nullptr;
    PyObject* limit = nullptr;
    PyObject* memory = nullptr;
    PyObject* io_error = nullptr; ///< io_error(message, path, errno): the instance
};
ErrorTypes g_errors;

void load_error_types() {
    py::module_ errors = py::module_::import("sss._errors");
    const auto get = [&](const char* name) {
        return py::object(errors.attr(name)).release().ptr();
    };
    g_errors.error = get("Error");
    g_errors.usage = get("UsageError");
    g_errors.format = get("FormatError");
    g_errors.value = get("ValueError");
    g_errors.limit = get("LimitError");
    g_errors.memory = get("OutOfMemoryError");
    g_errors.io_error = get("io_error");
}

/// Raises what make(*args) returns: an exception class (its constructor
/// takes the message first) or a function that makes the instance.
template <class... Args>
void raise(PyObject* make, Args&&... args) {
    try {
        py::object exc =
            py::reinterpret_borrow<py::object>(make)(std::forward<Args>(args)...);
        PyErr_SetObject(reinterpret_cast<PyObject*>(Py_TYPE(exc.ptr())), exc.ptr());
    } catch (py::error_already_set& e) {
        e.restore(); // making the exception failed: raise why
    }
}

py::object path_object(const std::string& path) {
    return path.empty() ? py::object(py::none()) : py::object(py::str(path));
}

void translate_exception(std::exception_ptr p) {
    try {
        if (p) std::rethrow_exception(p);
    } catch (const sss::IoError& e) {
        raise(g_errors.io_error, e.what(), path_object(e.path()), e.error_number());
    } catch (const sss::FormatError& e) {
        raise(g_errors.format, e.what(), path_object(e.path()),
              e.point() >= 0 ? py::object(py::int_(e.point())) : py::object(py::none()));
    } catch (const sss::MissingFrameError& e) {
        // The cli adds "-frame N" (sss::option_wording); here it is a keyword.
        raise(g_errors.usage, std::string(e.what()) + "; give the frame with frame=N");
    } catch (const sss::UsageError& e) {
        raise(g_errors.usage, e.what());
    } catch (const sss::ValueError& e) {
        raise(g_errors.value, e.what());
    } catch (const sss::OutOfMemoryError& e) {
        raise(g_errors.memory, e.what());
    } catch (const sss::LimitError& e) {
        raise(g_errors.limit, e.what());
    } catch (const sss::Error& e) {
        raise(g_errors.error, e.what());
    }
}

// ---------------------------------------------------------------------------
// Progress callbacks and cancellation
// ---------------------------------------------------------------------------

/// Thrown through the library when the Python side asks to stop (the
/// callback raised, or a signal such as Ctrl-C arrived). Not a std::exception,
/// so that no library handler mistakes it for one of its own errors.
struct Cancelled {};

/// A sss::Progress for one call: each time the percentage grows it takes the
/// GIL, lets Python handle pending signals and calls the user's callback with
/// (done, total). An exception there is kept and the run is cancelled by
/// throwing Cancelled; run() raises the kept exception in the caller.
class PythonProgress {
public:
    explicit PythonProgress(py::object callback) : m_callback(std::move(callback)) {
        m_progress.set_callback([this](uint64_t done, uint64_t total) {
            py::gil_scoped_acquire gil;
            // Another thread's step already cancelled: keep its exception.
            if (m_error) throw Cancelled{};
            if (PyErr_CheckSignals() != 0) {
                m_error.emplace();
                throw Cancelled{};
            }
            if (m_callback.is_none()) return;
            try {
                m_callback(done, total);
            } catch (py::error_already_set& e) {
                m_error.emplace(std::move(e));
                throw Cancelled{};
            }
        });
    }
    sss::Progress* get() { return &m_progress; }

    /// Runs f without the GIL; a cancellation raises the kept Python error.
    template <class F>
    auto run(F&& f) {
        try {
            py::gil_scoped_release release;
            return f();
        } catch (const Cancelled&) {
            if (m_error) throw std::move(*m_error);
            throw std::runtime_error("sss: run cancelled");
        }
    }

private:
    py::object m_callback;
    sss::Progress m_progress{false};
    std::optional<py::error_already_set> m_error;
};

// ---------------------------------------------------------------------------
// Clouds <-> dicts of numpy arrays
// ---------------------------------------------------------------------------

/// A float32 array over a vector's storage, which the array then owns (no copy).
template <class T>
py::array own_array(std::vector<T>&& v, std::vector<py::ssize_t> shape) {
    auto* holder = new std::vector<T>(std::move(v));
    py::capsule owner(holder, [](void* p) { delete static_cast<std::vector<T>*>(p); });
    return py::array_t<float>(shape, reinterpret_cast<const float*>(holder->data()),
                              owner);
}

std::vector<py::ssize_t> channel_shape(std::size_t n, sss::ChannelType type) {
    const auto count = static_cast<py::ssize_t>(n);
    switch (sss::channel_type_size(type)) {
    case 1:
        return {count};
    case 16:
        return {count, 4, 4};
    default:
        return {count, 3};
    }
}

py::list matrix_list(const std::array<float, 16>& m) {
    py::list out;
    for (float v : m) out.append(v);
    return out;
}

/// (arrays, types, header) of a cloud, its storage moved into the arrays.
py::tuple cloud_to_python(sss::PointCloud&& cloud) {
    const std::size_t n = cloud.size();
    py::dict arrays, types, header;
    arrays["P"] = own_array(std::move(cloud.positions), {py::ssize_t(n), 3});
    arrays["N"] = own_array(std::move(cloud.normals), {py::ssize_t(n), 3});
    arrays["radius"] = own_array(std::move(cloud.radii), {py::ssize_t(n)});
    for (sss::Channel& c : cloud.channels) {
        types[py::str(c.name)] = sss::channel_type_name(c.type);
        arrays[py::str(c.name)] = own_array(std::move(c.data), channel_shape(n, c.type));
    }
    header["world_to_eye"] = matrix_list(cloud.world_to_eye);
    header["world_to_ndc"] = matrix_list(cloud.world_to_ndc);
    header["format"] = py::make_tuple(cloud.format[0], cloud.format[1], cloud.format[2]);
    header["file_version"] = cloud.file_version;
    header["compressed"] = cloud.file_compressed;
    return py::make_tuple(arrays, types, header);
}

/// The values of an array as n x width floats (converted to float32, copied).
std::vector<float> array_values(const std::string& name, const py::handle& value,
                                std::size_t n, int width) {
    auto a = py::array_t<float, py::array::c_style | py::array::forcecast>::ensure(value);
    if (!a) throw sss::ValueError("cloud['" + name + "']: not a numeric array");
    const auto count = static_cast<std::size_t>(a.size());
    const bool rows_ok = a.ndim() >= 1 && std::size_t(a.shape(0)) == n;
    if (!rows_ok || count != n * std::size_t(width))
        throw sss::ValueError("cloud['" + name + "']: expected " + std::to_string(n) +
                              " rows of " + std::to_string(width) +
                              " values, got an array of " + std::to_string(count) +
                              " values");
    std::vector<float> out(count);
    if (count) std::memcpy(out.data(), a.data(), count * sizeof(float));
    return out;
}

std::vector<glm::vec3> vec3_values(const std::string& name, const py::handle& value,
                                   std::size_t n) {
    std::vector<float> f = array_values(name, value, n, 3);
    std::vector<glm::vec3> out(n);
    if (n) std::memcpy(static_cast<void*>(out.data()), f.data(), n * 3 * sizeof(float));
    return out;
}

/// A header value as one row of floats, whatever its shape; ValueError when
/// it is not numeric (ensure() gives a null array then, which must not be
/// reshaped).
py::array_t<float> header_row(const std::string& name, const py::handle& value) {
    auto a = py::array_t<float, py::array::c_style | py::array::forcecast>::ensure(value);
    if (!a) throw sss::ValueError("header['" + name + "']: not a numeric array");
    return a.reshape({py::ssize_t(1), py::ssize_t(a.size())});
}

std::array<float, 16> matrix_value(const std::string& name, const py::handle& value) {
    std::vector<float> f = array_values(name, header_row(name, value), 1, 16);
    std::array<float, 16> m;
    std::copy(f.begin(), f.end(), m.begin());
    return m;
}

/// The cloud of (arrays, types, header): P required; N (zero: no normal) and
/// radius (zero) optional; other keys are channels whose type is types[name],
/// else float, color or matrix by their width.
sss::PointCloud cloud_from_python(const py::dict& arrays, const py::dict& types,
                                  const py::dict& header) {
    if (!arrays.contains("P"))
        throw sss::ValueError("cloud has no 'P' array (positions)");
    auto p = py::array::ensure(arrays["P"]);
    if (!p || p.ndim() < 1) throw sss::ValueError("cloud['P']: not an (N, 3) array");
    const auto n = static_cast<std::size_t>(p.shape(0));
    sss::PointCloud cloud;
    cloud.positions = vec3_values("P", arrays["P"], n);
    cloud.normals = arrays.contains("N") ? vec3_values("N", arrays["N"], n)
                                         : std::vector<glm::vec3>(n, glm::vec3(0.0f));
    cloud.radii = arrays.contains("radius")
                      ? array_values("radius", arrays["radius"], n, 1)
                      : std::vector<float>(n, 0.0f);
    for (auto item : arrays) {
        const std::string name = py::str(item.first);
        if (name == "P" || name == "N" || name == "radius") continue;
        sss::ChannelType type = sss::ChannelType::Float;
        if (types.contains(name)) {
            const std::string t = py::str(types[py::str(name)]);
            auto parsed = sss::parse_channel_type(t);
            if (!parsed)
                throw sss::ValueError("channel '" + name + "': unknown type '" + t +
                                      "' (float, color, point, vector, normal, matrix)");
            type = *parsed;
        } else {
            auto a = py::array::ensure(item.second);
            const py::ssize_t width = a && a.ndim() >= 1 && a.shape(0) > 0
                                          ? a.size() / a.shape(0)
                                          : (a && a.ndim() > 1 ? a.shape(1) : 1);
            type = width == 3    ? sss::ChannelType::Color
                   : width == 16 ? sss::ChannelType::Matrix
                                 : sss::ChannelType::Float;
        }
        sss::Channel c;
        c.name = name;
        c.type = type;
        c.data = array_values(name, item.second, n, sss::channel_type_size(type));
        cloud.channels.push_back(std::move(c));
    }
    if (header.contains("world_to_eye"))
        cloud.world_to_eye = matrix_value("world_to_eye", header["world_to_eye"]);
    if (header.contains("world_to_ndc"))
        cloud.world_to_ndc = matrix_value("world_to_ndc", header["world_to_ndc"]);
    if (header.contains("format")) {
        std::vector<float> f =
            array_values("format", header_row("format", header["format"]), 1, 3);
        cloud.format = {f[0], f[1], f[2]};
    }
    return cloud;
}

py::tuple read_cloud(const std::string& path) {
    sss::PointCloud cloud;
    {
        py::gil_scoped_release release;
        cloud = sss::read_point_cloud(path);
    }
    return cloud_to_python(std::move(cloud));
}

void write_cloud(const std::string& path, const py::dict& arrays, const py::dict& types,
                 const py::dict& header, int ptc_version, bool compress) {
    const sss::PointCloud cloud = cloud_from_python(arrays, types, header);
    sss::PointCloudWriteOptions options;
    options.ptc_version = ptc_version;
    options.compress = compress;
    py::gil_scoped_release release;
    sss::write_point_cloud(cloud, path, options);
}

// ---------------------------------------------------------------------------
// Diffusion (ptfilter -ssdiffusion)
// ---------------------------------------------------------------------------

/// A ptfilter run's options from the words of its command line (without
/// files), parsed by the cli's own option parsers.
struct FilterCall {
    sss::SsDiffusionOptions options;
    sss::PointCloudWriteOptions write;
    sss::RunOptions running;
};

FilterCall parse_filter_words(const std::vector<std::string>& words, bool file_options) {
    FilterCall call;
    sss::ArgScanner args(words);
    std::vector<std::string> stray;
    std::string o;
    while (args.next_option(o, stray)) {
        if (sss::ssdiffusion_option(args, o, call.options)) continue;
        if ((o == "threads" || (file_options && o == "frame")) &&
            sss::run_option(args, o, call.running))
            continue;
        if (file_options && sss::write_option(args, o, call.write)) continue;
        throw sss::UsageError("unknown keyword '" + o + "'");
    }
    if (!stray.empty()) throw sss::UsageError("unexpected value '" + stray.front() + "'");
    return call;
}

/// The keyword that names a channel of each role (ptfilter names its option).
const char* channel_keyword(sss::MissingChannelError::Role role) {
    switch (role) {
    case sss::MissingChannelError::Role::Radiance:
        return "radiancechannel=";
    case sss::MissingChannelError::Role::Albedo:
        return "albedo='fromfile'";
    case sss::MissingChannelError::Role::Dmfp:
        return "diffusemeanfreepath='fromfile'";
    }
    return "?";
}

py::dict report_dict(const sss::SsDiffusionReport& r) {
    py::dict d;
    d["material"] = r.material_lines;
    d["warnings"] = r.warnings;
    d["seconds"] = r.seconds;
    d["octree_nodes"] = r.stats.nodes;
    d["build_seconds"] = r.stats.build_seconds;
    d["eval_seconds"] = r.stats.eval_seconds;
    d["isa"] = sss::isa_name(r.stats.isa);
    if (r.volume.needed || r.volume.seconds > 0) {
        const sss::VolumeReport& v = r.volume;
        py::dict vd;
        vd["thin_points"] = v.thin_points;
        vd["voxel"] = v.voxel;
        vd["unknowns"] = v.unknowns;
        vd["seconds"] = v.seconds;
        const auto rgb = [](const glm::dvec3& x) {
            return py::make_tuple(x.x, x.y, x.z);
        };
        vd["flux_in"] = rgb(v.flux_in);
        vd["flux_out"] = rgb(v.flux_out);
        vd["flux_blocked"] = rgb(v.flux_blocked);
        vd["transmission_min"] = rgb(v.transmission_min);
        vd["transmission_max"] = rgb(v.transmission_max);
        d["volume"] = vd;
    }
    return d;
}

/// Runs f (the filter) and gives a missing channel ptfilter's form, with the
/// keyword to set (the input files are named by the library).
template <class F>
void filter_errors(F&& f) {
    try {
        f();
    } catch (const sss::MissingChannelError& e) {
        throw sss::ValueError(e.inputs() + ": input has no channel '" + e.channel() +
                              "' (set it with " + channel_keyword(e.role()) +
                              "; channels present: " + e.present() + ")");
    }
}

/// ssdiffusion() of a cloud given as (arrays, types, header) or read from
/// files: (arrays, types, header, report) of the output.
py::tuple ssdiffusion(const py::object& source, const std::vector<std::string>& words,
                      const py::object& callback) {
    FilterCall call = parse_filter_words(words, false);
    // What ptfilter checks before reading anything (prepare_filter_job()).
    call.options.diffusion.isa = sss::resolve_isa(call.options.diffusion.isa);
    sss::describe_material(call.options);
    sss::PointCloud input;
    std::vector<std::string> paths;
    if (py::isinstance<py::tuple>(source)) {
        py::tuple t = source;
        input = cloud_from_python(t[0], t[1], t[2]);
    } else {
        paths = source.cast<std::vector<std::string>>();
        if (paths.empty()) throw sss::UsageError("ssdiffusion: no input file given");
    }
    PythonProgress progress(callback);
    call.options.diffusion.progress = progress.get();
    sss::SsDiffusionReport report;
    sss::PointCloud out = progress.run([&] {
        sss::ThreadLimit limit(sss::resolve_thread_count(call.running.threads));
        for (std::size_t i = 0; i < paths.size(); ++i) {
            if (i == 0)
                input = sss::read_point_cloud(paths[i]);
            else
                input.append(sss::read_point_cloud(paths[i]));
        }
        sss::PointCloud result;
        const std::string what = paths.empty() ? std::string("cloud") : sss::join(paths);
        filter_errors([&] {
            try {
                result = sss::ssdiffusion(input, call.options, &report);
            } catch (const sss::MissingChannelError& e) {
                throw sss::MissingChannelError(e.role(), e.channel(), e.present(), what);
            } catch (const sss::ValueError& e) {
                throw sss::ValueError(what + ": " + e.what());
            }
        });
        return result;
    });
    py::tuple t = cloud_to_python(std::move(out));
    return py::make_tuple(t[0], t[1], t[2], report_dict(report));
}

/// ptfilter -ssdiffusion [options] inputs... output, file to file in little
/// memory: the tool's own library call (sss::run_filter_job()), so the output
/// is byte for byte ptfilter's.
py::dict ptfilter(std::vector<std::string> inputs, std::string output,
                  const std::vector<std::string>& words, const py::object& callback) {
    FilterCall call = parse_filter_words(words, true);
    if (inputs.empty()) throw sss::UsageError("ptfilter: no input file given");
    sss::FilterJob job;
    job.inputs = std::move(inputs);
    job.output = std::move(output);
    job.options = call.options;
    job.write = call.write;
    sss::prepare_filter_job(job, call.running.frame);
    PythonProgress progress(callback);
    job.options.diffusion.progress = progress.get();
    sss::FilterJobReport report;
    progress.run([&] {
        sss::ThreadLimit limit(sss::resolve_thread_count(call.running.threads));
        filter_errors([&] { report = sss::run_filter_job(job); });
        return 0;
    });
    return report_dict(report.diffusion);
}

// ---------------------------------------------------------------------------
// Brick maps
// ---------------------------------------------------------------------------

/// brickmake's options from the words of its command line, parsed by the
/// cli's brickmake_option() as brickmake's own are.
std::pair<sss::BrickMapBuildOptions, sss::RunOptions>
parse_brickmake_words(const std::vector<std::string>& words) {
    sss::BrickMapBuildOptions opt;
    sss::RunOptions running;
    sss::ArgScanner args(words);
    std::vector<std::string> stray;
    std::string o;
    while (args.next_option(o, stray)) {
        if (sss::brickmake_option(args, o, opt)) {
            continue;
        } else if ((o == "threads" || o == "frame") &&
                   sss::run_option(args, o, running)) {
            continue;
        } else {
            throw sss::UsageError("unknown keyword '" + o + "'");
        }
    }
    if (!stray.empty()) throw sss::UsageError("unexpected value '" + stray.front() + "'");
    return {opt, running};
}

py::dict make_brickmap(const py::object& source, std::string output,
                       const std::vector<std::string>& words,
                       const py::object& callback) {
    auto [opt, running] = parse_brickmake_words(words);
    opt.provenance = sss::quoted_command_line(
        std::string("sss.make_brickmap (Python) ") + sss::version_string(), words);
    std::vector<sss::PointCloud> clouds;
    std::vector<std::string> paths;
    if (py::isinstance<py::list>(source) && py::len(source) > 0 &&
        py::isinstance<py::tuple>(py::list(source)[0])) {
        for (py::handle h : source) {
            py::tuple t = py::reinterpret_borrow<py::tuple>(h);
            clouds.push_back(cloud_from_python(t[0], t[1], t[2]));
        }
    } else {
        paths = source.cast<std::vector<std::string>>();
        for (std::string& f : paths)
            f = sss::expand_frame_pattern(f, running.frame, "file name");
    }
    output = sss::expand_frame_pattern(output, running.frame, "file name");
    PythonProgress progress(callback);
    opt.progress = progress.get();
    const sss::BrickMapBuildReport r = progress.run([&] {
        sss::ThreadLimit limit(sss::resolve_thread_count(running.threads));
        sss::check_output_target(output);
        if (!paths.empty()) return sss::make_brick_map_from_files(paths, opt, output);
        return sss::build_brick_map(clouds, opt, output);
    });
    py::dict d;
    d["points"] = r.points;
    d["bricks_before_pruning"] = r.bricks_before_pruning;
    d["bricks"] = r.bricks_written;
    d["file_size"] = r.file_size;
    d["seconds"] = r.seconds;
    return d;
}

py::dict brickmap_info(const sss::BrickMap& map) {
    const sss::BrickMapInfo& i = map.info();
    py::dict d;
    py::list channels;
    for (const auto& [name, type] : i.channels)
        channels.append(py::make_tuple(name, sss::channel_type_name(type)));
    d["version"] = i.version;
    d["channels"] = channels;
    d["data_size"] = i.data_size;
    d["bbox_min"] = py::make_tuple(i.bbox_min.x, i.bbox_min.y, i.bbox_min.z);
    d["bbox_max"] = py::make_tuple(i.bbox_max.x, i.bbox_max.y, i.bbox_max.z);
    d["cube_min"] = py::make_tuple(i.cube_min.x, i.cube_min.y, i.cube_min.z);
    d["cube_side"] = i.cube_side;
    d["max_depth"] = i.max_depth;
    d["max_error"] = i.max_error;
    d["ignore_normals"] = i.ignore_normals;
    d["omit_geometry"] = i.omit_geometry;
    d["world_to_eye"] = matrix_list(i.world_to_eye);
    d["world_to_ndc"] = matrix_list(i.world_to_ndc);
    d["format"] = py::make_tuple(i.format[0], i.format[1], i.format[2]);
    d["provenance"] = i.provenance;
    d["total_bricks"] = i.total_bricks;
    d["total_samples"] = i.total_samples;
    d["levels"] = i.levels.size();
    d["file_size"] = i.file_size;
    return d;
}

// ---------------------------------------------------------------------------
// texture3d lookups (brick maps and point clouds), many points per call
// ---------------------------------------------------------------------------

/// The points, normals and filter radii of a lookup call.
struct LookupQuery {
    std::vector<glm::vec3> points;
    std::vector<glm::vec3> normals; ///< empty: no normals
    std::vector<float> radii;       ///< empty: `radius` for every point
    float radius = 0.0f;
};

LookupQuery lookup_query(const py::object& points, const py::object& normals,
                         const py::object& filter_radius) {
    auto pts =
        py::array_t<float, py::array::c_style | py::array::forcecast>::ensure(points);
    if (!pts || pts.ndim() != 2 || pts.shape(1) != 3)
        throw sss::ValueError("lookup: points must be an (N, 3) array");
    const std::size_t n = std::size_t(pts.shape(0));
    LookupQuery q;
    q.points = vec3_values("points", pts, n);
    if (!normals.is_none()) q.normals = vec3_values("normals", normals, n);
    auto r = py::array_t<float, py::array::c_style | py::array::forcecast>::ensure(
        filter_radius);
    if (!r)
        throw sss::ValueError("lookup: filterradius must be a number or an (N,) array");
    if (r.ndim() == 0)
        q.radius = *r.data();
    else
        q.radii = array_values("filterradius", r, n, 1);
    return q;
}

/// A channel of a 3-D texture: its name and where its floats are.
struct TextureChannel {
    std::string name;
    int offset = 0;
    int floats = 0;
};

/// The ranges of the channels asked for: a name, a list of names, or None
/// for every channel in order. ValueError names what the texture has.
std::vector<sss::PointCloudLookup::Range>
select_channels(const std::vector<TextureChannel>& channels, const py::object& channel,
                const char* what) {
    std::vector<std::string> names;
    if (channel.is_none()) {
        for (const TextureChannel& c : channels) names.push_back(c.name);
    } else if (py::isinstance<py::str>(channel)) {
        names.push_back(channel.cast<std::string>());
    } else {
        names = channel.cast<std::vector<std::string>>();
    }
    std::vector<sss::PointCloudLookup::Range> ranges;
    for (const std::string& name : names) {
        const TextureChannel* found = nullptr;
        for (const TextureChannel& c : channels)
            if (c.name == name) found = &c;
        if (!found) {
            std::string have;
            for (const TextureChannel& c : channels)
                have += (have.empty() ? "" : ", ") + c.name;
            throw sss::ValueError(std::string("lookup: the ") + what +
                                  " has no channel '" + name +
                                  "' (channels: " + (have.empty() ? "none" : have) + ")");
        }
        ranges.push_back({found->offset, found->floats});
    }
    return ranges;
}

int range_floats(const std::vector<sss::PointCloudLookup::Range>& ranges) {
    int width = 0;
    for (const auto& r : ranges) width += r.floats;
    return width;
}

/// Runs lookup(p, n, radius, out_row) for every point without the GIL, in
/// parallel over blocks of 1024 points: (N, width) float32 values (0 where
/// it returned false) and (N,) bool "found" flags.
template <class F>
py::tuple run_lookups(const LookupQuery& q, int width, int threads, F&& lookup) {
    const std::size_t n = q.points.size();
    std::vector<float> out(n * std::size_t(width));
    std::vector<uint8_t> found(n);
    {
        py::gil_scoped_release release;
        sss::ThreadLimit limit(sss::resolve_thread_count(threads));
        tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, 1024),
                          [&](const tbb::blocked_range<std::size_t>& range) {
                              for (std::size_t i = range.begin(); i != range.end(); ++i) {
                                  const glm::vec3 normal =
                                      q.normals.empty() ? glm::vec3(0.0f) : q.normals[i];
                                  const float r = q.radii.empty() ? q.radius : q.radii[i];
                                  float* row = out.data() + i * std::size_t(width);
                                  found[i] = lookup(q.points[i], normal, r, row);
                                  if (!found[i]) std::fill(row, row + width, 0.0f);
                              }
                          });
    }
    py::array values = own_array(std::move(out), {py::ssize_t(n), py::ssize_t(width)});
    py::array_t<bool> hit{py::ssize_t(n)};
    if (n) std::memcpy(hit.mutable_data(), found.data(), n);
    return py::make_tuple(values, hit);
}

std::vector<TextureChannel> brickmap_channels(const sss::BrickMap& map) {
    std::vector<TextureChannel> out;
    for (const auto& [name, type] : map.info().channels)
        out.push_back({name, map.channel_offset(name), sss::channel_type_size(type)});
    return out;
}

/// texture3d at many points of a brick map.
py::tuple brickmap_lookup(const sss::BrickMap& map, const py::object& points,
                          const py::object& channel, const py::object& normals,
                          const py::object& filter_radius, int threads) {
    const LookupQuery q = lookup_query(points, normals, filter_radius);
    const auto ranges = select_channels(brickmap_channels(map), channel, "brick map");
    const int data_size = std::max(map.info().data_size, 1);
    return run_lookups(q, range_floats(ranges), threads,
                       [&](const glm::vec3& p, const glm::vec3& n, float r, float* row) {
                           thread_local std::vector<float> sample;
                           sample.resize(std::size_t(data_size));
                           const bool hit = map.lookup(p, n, r, sample.data());
                           for (const auto& range : ranges) {
                               std::memcpy(row, sample.data() + range.offset,
                                           std::size_t(range.floats) * sizeof(float));
                               row += range.floats;
                           }
                           return hit;
                       });
}

/// A point cloud opened for texture3d lookups as the renderer does them
/// (sss::CloudTexture3d): from a file or from (arrays, types, header).
std::unique_ptr<sss::CloudTexture3d> open_cloud_texture(const py::object& source) {
    if (py::isinstance<py::tuple>(source)) {
        py::tuple t = source;
        sss::PointCloud cloud = cloud_from_python(t[0], t[1], t[2]);
        py::gil_scoped_release release;
        return std::make_unique<sss::CloudTexture3d>(std::move(cloud));
    }
    const std::string path = source.cast<std::string>();
    py::gil_scoped_release release;
    return std::make_unique<sss::CloudTexture3d>(sss::read_point_cloud(path));
}

py::list cloud_texture_channels(const sss::CloudTexture3d& tex) {
    py::list out;
    for (const auto& c : tex.channels())
        out.append(py::make_tuple(c.name, sss::channel_type_name(c.type)));
    return out;
}

/// texture3d at many points of a point cloud.
py::tuple cloud_texture_lookup(const sss::CloudTexture3d& tex, const py::object& points,
                               const py::object& channel, const py::object& normals,
                               const py::object& filter_radius, int threads) {
    const LookupQuery q = lookup_query(points, normals, filter_radius);
    std::vector<TextureChannel> channels;
    for (const auto& c : tex.channels()) channels.push_back({c.name, c.offset, c.floats});
    const auto ranges = select_channels(channels, channel, "point cloud");
    return run_lookups(q, range_floats(ranges), threads,
                       [&](const glm::vec3& p, const glm::vec3& n, float r, float* row) {
                           return tex.lookup(p, n, r, ranges, row);
                       });
}

} // namespace

PYBIND11_MODULE(_sss, m) {
    m.doc() = "sss: the binding of the sss library (use the `sss` package)";

    load_error_types();
    py::register_exception_translator(translate_exception);

    m.attr("__version__") = sss::version_string();

    m.def("read_cloud", &read_cloud, py::arg("path"));
    m.def("write_cloud", &write_cloud, py::arg("path"), py::arg("arrays"),
          py::arg("types"), py::arg("header"), py::arg("ptc_version"),
          py::arg("compress"));
    m.def("ssdiffusion", &ssdiffusion, py::arg("source"), py::arg("words"),
          py::arg("callback"));
    m.def("ptfilter", &ptfilter, py::arg("inputs"), py::arg("output"), py::arg("words"),
          py::arg("callback"));
    m.def("make_brickmap", &make_brickmap, py::arg("source"), py::arg("output"),
          py::arg("words"), py::arg("callback"));
    m.def("has_frame_pattern", &sss::has_frame_pattern, py::arg("path"));
    m.def("expand_frame_pattern", &sss::expand_frame_pattern, py::arg("path"),
          py::arg("frame") = py::none(), py::arg("what") = "path");
    m.def("isa_names", [] {
        std::vector<std::string> out;
        for (sss::Isa isa : sss::supported_isas()) out.push_back(sss::isa_name(isa));
        return out;
    });

    py::class_<sss::BrickMap>(m, "BrickMap")
        .def(py::init([](const std::string& path, std::size_t cache_bytes) {
                 py::gil_scoped_release release;
                 return std::make_unique<sss::BrickMap>(path, cache_bytes);
             }),
             py::arg("path"), py::arg("cache_bytes") = std::size_t(256u << 20))
        .def_property_readonly("info", &brickmap_info)
        .def("lookup", &brickmap_lookup, py::arg("points"), py::arg("channel"),
             py::arg("normals"), py::arg("filterradius"), py::arg("threads"))
        .def("verify",
             [](const sss::BrickMap& map) {
                 py::gil_scoped_release release;
                 return map.verify();
             })
        .def_property_readonly("bricks_loaded", &sss::BrickMap::bricks_loaded)
        .def_property_readonly("cached_bytes", &sss::BrickMap::cached_bytes);

    py::class_<sss::CloudTexture3d>(m, "CloudTexture3d")
        .def(py::init(&open_cloud_texture), py::arg("source"))
        .def_property_readonly("channels", &cloud_texture_channels)
        .def_property_readonly("data_size", &sss::CloudTexture3d::data_size)
        .def_property_readonly(
            "size", [](const sss::CloudTexture3d& t) { return t.cloud().size(); })
        .def("lookup", &cloud_texture_lookup, py::arg("points"), py::arg("channel"),
             py::arg("normals"), py::arg("filterradius"), py::arg("threads"));
}
