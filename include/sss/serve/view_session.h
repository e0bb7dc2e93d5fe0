// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
#pragma once
/// \file view_session.h
/// What `ptview -serve` shows and computes, without the HTTP around it: the
/// files given (point clouds and brick maps, read once at start), their data
/// as arrays of floats for the page, the live diffusion of a baked cloud
/// (ssdiffusion() on a subsample while a slider moves, on the whole cloud
/// when it is let go; a newer request cancels an older one), saving a result
/// and turntable pictures. serve.h puts it on the network.

#include <cstddef>
#include <cstdint>
#include <functional>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <vector>

#include "sss/cloud/point_cloud.h"
#include "sss/diffusion/ssdiffusion.h"
#include "sss/util/error.h"

namespace sss {

class BrickMap;

/// A request for something the session does not have (an unknown source,
/// channel, cloud or depth): HTTP 404.
class NotFoundError : public Error {
public:
    explicit NotFoundError(const std::string& what) : Error(what) {}
};

/// Turns the page's ptfilter option words ("-material", "skin1",
/// "-diffusemeanfreepath", "1", "2", "3") into diffusion options. The tool
/// gives it (only the command line knows option names); it throws UsageError
/// for a word it refuses.
using DiffusionWordParser =
    std::function<SsDiffusionOptions(const std::vector<std::string>& words)>;
/// The command line that computes a result: `ptfilter -ssdiffusion WORDS
/// input output`, quoted for a POSIX shell.
using DiffusionCommand =
    std::function<std::string(const std::vector<std::string>& words,
                              const std::string& input, const std::string& output)>;

/// What `ptview -serve` is told.
struct ServeOptions {
    /// Point clouds (.ptc, .ply) and brick maps (.bkm), as given; the page
    /// names them so, and asks for them by index only.
    std::vector<std::string> inputs;
    std::string bind_address = "127.0.0.1";
    int port = 0; ///< 0: a free port chosen by the system
    /// Where Save and turntables write; empty: the folder of the input the
    /// result comes from (a turntable: of the first input).
    std::string save_dir;
    /// About how many points the live diffusion computes while a slider
    /// moves (every k-th point of the cloud); a cloud of at most this many
    /// is always computed whole.
    std::size_t live_points = 50000;
    DiffusionWordParser parse_diffusion;
    DiffusionCommand diffusion_command;
    /// The video encoder for turntables, searched on PATH; empty: none.
    std::string ffmpeg = "ffmpeg";
    /// The Software attribute of pictures written ("sss ptview 0.1.0").
    std::string software;
    /// Receives a line per request answered (method, path, status); null:
    /// quiet.
    std::function<void(const std::string& line)> log;
};

/// One thing the page can draw, by its id: "c<i>" input i (a point cloud),
/// "b<i>.<depth>" the voxels of brick map i at a depth, "l<i>" the last
/// whole live diffusion of cloud i.
struct ViewSourceId {
    enum class Kind { Cloud, BrickLevel, Live };
    Kind kind = Kind::Cloud;
    std::size_t input = 0;
    int depth = 0;
    /// Parses an id; NotFoundError for anything else (nothing is read from a
    /// request but these digits).
    static ViewSourceId parse(const std::string& text);
    std::string text() const;
};

/// A live diffusion request.
struct LiveRequest {
    std::size_t cloud = 0;          ///< input index
    std::vector<std::string> words; ///< ptfilter option words
    bool preview = false;           ///< on the subsample (while dragging)
    /// The name Save would write, for the command line shown; "" (or a name
    /// Save refuses): default_result_name() of the input.
    std::string output_name;
};

/// The name a result of `input` is saved under by default: its file name
/// without folder and extension, then "_ssd.ptc" ("teapot_ssd.ptc").
std::string default_result_name(const std::string& input);

/// A live diffusion result.
struct LiveResult {
    std::size_t stride = 1; ///< the points computed: every stride-th of the cloud
    std::size_t points = 0;
    /// The output channel, 3 floats per point computed.
    std::vector<float> values;
    std::string command;               ///< the ptfilter command line of this result
    double seconds = 0;                ///< the diffusion alone
    uint32_t hash = 0;                 ///< value_hash() of values
    std::vector<std::string> material; ///< describe_material() lines
    std::vector<std::string> warnings;
};

/// FNV-1a (32-bit) of floats' bytes: the page computes the same over what it
/// received and shows it, so that a test can tie the picture to a file.
uint32_t value_hash(const std::vector<float>& values);

/// A turntable: frames of an orbit around the tiles' sources, drawn with
/// ptview's renderer (render_point_view) and written as PNG pictures, and a
/// video when ffmpeg is there.
struct TurntableRequest {
    struct Tile {
        std::string source;  ///< a ViewSourceId text
        std::string channel; ///< a channel, N, radius, NAME:lum; "" = default
    };
    std::vector<Tile> tiles;
    std::string name; ///< the folder and file prefix (a plain file name)
    int frames = 36;
    double start_azimuth = 0.0;
    double elevation = 20.0;
    int up_axis = 1;
    double fov = 30.0;
    int width = 512, height = 512;
    std::optional<double> exposure; ///< nullopt: the first frame's automatic one
    bool false_color = true;
    float radius_scale = 1.0f;
    std::string video = "mp4"; ///< mp4, webm or none
    bool overwrite = false;
};

struct TurntableResult {
    std::string folder;
    std::vector<std::string> frames; ///< file names in the folder
    std::string video;               ///< file name, "" when none was made
    std::string video_note;          ///< why there is none
    double exposure = 0;
};

/// The files of one `ptview -serve` run and what the page asked of them.
/// Thread-safe: the server calls it from several threads.
class ViewSession {
public:
    /// Reads every input (a cloud whole; a brick map's header and tables):
    /// the readers' errors (IoError, FormatError) name the file, as every
    /// tool's do. UsageError for an input that is neither a cloud nor a map.
    explicit ViewSession(ServeOptions options);
    ~ViewSession();
    ViewSession(const ViewSession&) = delete;
    ViewSession& operator=(const ViewSession&) = delete;

    const ServeOptions& options() const { return m_options; }

    /// Everything the page needs to start, as JSON: the inputs (label, kind,
    /// points, channels, bounds, camera, brick levels, whether a live
    /// diffusion can run), the material presets with their albedo and mean
    /// free path, the profiles, whether turntables get a video.
    std::string scene_json() const;

    /// A source's points: 7 floats per point (position, normal, radius).
    std::vector<float> geometry(const std::string& source) const;
    /// One channel of a source, `components` floats per point: channel k of
    /// its list in scene_json().
    std::vector<float> channel(const std::string& source, std::size_t k) const;

    /// Runs the live diffusion. A newer call (of any cloud) cancels this one:
    /// it then throws Cancelled. UsageError for words the parser refuses,
    /// ValueError for a material the library refuses, NotFoundError for an
    /// input that is not a baked cloud.
    LiveResult diffuse(const LiveRequest& request);

    /// Writes the whole diffusion of `words` (computed again unless it is
    /// the last whole result) atomically to `name` in the save folder.
    /// `name` must be a plain file name ending in .ptc or .ply; an existing
    /// file is replaced only with `overwrite`, an input never. Returns the
    /// path written and its result (command and hash).
    std::pair<std::string, LiveResult> save(std::size_t cloud,
                                            const std::vector<std::string>& words,
                                            const std::string& name, bool overwrite);

    TurntableResult turntable(const TurntableRequest& request);

    /// Input i's file name as given; NotFoundError beyond the inputs.
    const std::string& input_path(std::size_t i) const;
    /// The folder results of input `input` are written to.
    std::string save_folder(std::size_t input) const;

private:
    struct Input;
    const Input& input(std::size_t i) const;
    std::shared_ptr<const PointCloud> source_cloud(const ViewSourceId& id) const;
    std::shared_ptr<const PointCloud> live_subsample(std::size_t cloud,
                                                     std::size_t& stride);
    /// ticket 0: never cancelled. `kept`: the output cloud of a whole run.
    LiveResult compute(std::size_t cloud, const LiveRequest& request, uint64_t ticket,
                       std::shared_ptr<const PointCloud>* kept = nullptr);

    ServeOptions m_options;
    std::vector<std::unique_ptr<Input>> m_inputs;
    mutable std::mutex m_mutex; ///< the caches below
    uint64_t m_ticket = 0;      ///< the newest live request
};

/// Whether `name` is a plain file name a result may be written under: no
/// folder, not "." or "..", no leading dot or dash, only letters, digits and
/// ._-+@ (so that the command line shown needs no quoting).
bool is_plain_file_name(const std::string& name);

} // namespace sss
