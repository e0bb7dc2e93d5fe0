// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
#pragma once
/// \file scene.h
/// The scene module owns the scene description (primitives, attributes,
/// lights, options and camera), the RIB reader (rib.h) and the OBJ import it
/// uses.
/// May use: util.
///
/// The scene layer shared by ptbake and render: what a RIB file describes,
/// resolved into world space. The RIB reader (rib.h) fills it; the dicer
/// (dice.h), the lights (lights.h) and the tools read it.
///
/// Matrix convention: glm column vectors, p_parent = M * p_child. RenderMan
/// writes matrices for row vectors (p * M); the 16 numbers of a RIB
/// `Transform` loaded column-major into a glm::dmat4 give exactly our M, and
/// `ConcatTransform m` becomes CTM = CTM * m. Camera space is RenderMan's:
/// left-handed, x right, y up, +z into the screen.

#include <array>
#include <cmath>
#include <limits>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include <glm/mat4x4.hpp>
#include <glm/vec2.hpp>
#include <glm/vec3.hpp>

#include "sss/util/messages.h"

namespace sss {

using Matrix4 = glm::dmat4;

/// The largest |coordinate| a world-space point of a diced surface, a camera
/// or a camera ray's origin may have (docs/scene.md, "Coordinate range"):
/// Embree drops triangles with a coordinate beyond 1.844e18 (FLT_LARGE)
/// without a word and aborts on rays that start there, and the float
/// arithmetic of ray offsets and squared distances overflows not far above.
/// 1e18 leaves room for ray offsets; at that distance from the origin a float
/// resolves 6.9e10 units, so no sensible scene comes near it.
constexpr double kMaxWorldCoordinate = 1e18;

/// Type of a RIB parameter ("float", "color", ...).
enum class ParamType {
    Float,
    Integer,
    String,
    Color,
    Point,
    Vector,
    Normal,
    HPoint,
    Matrix
};
/// Storage class of a RIB parameter (how many values a primitive carries).
enum class ParamClass { Constant, Uniform, Varying, Vertex, FaceVarying, FaceVertex };

/// Numbers per element of a type: 1 (float, integer, string), 3 (color,
/// point, vector, normal), 4 (hpoint) or 16 (matrix).
int param_type_components(ParamType type);
/// RIB spelling of a type ("float", "integer", ...).
const char* param_type_name(ParamType type);
/// The type spelled `name` in a RIB declaration ("integer" also as "int");
/// nullopt if unknown.
std::optional<ParamType> parse_param_type(std::string_view name);
/// RIB spelling of a storage class ("uniform", "facevarying", ...).
const char* param_class_name(ParamClass storage);
/// The storage class spelled `name`; nullopt if unknown.
std::optional<ParamClass> parse_param_class(std::string_view name);

/// One "name" value pair of a RIB parameter list, with its resolved
/// declaration (inline, `Declare`d or predeclared).
struct Param {
    std::string name; ///< bare name, without the inline declaration
    ParamType type = ParamType::Float;
    ParamClass storage = ParamClass::Uniform;
    int array_size = 1;               ///< "float[2] st" -> 2
    std::vector<double> numbers;      ///< all numbers, in RIB order
    std::vector<std::string> strings; ///< for String parameters
    /// False for a name neither declared inline nor by Declare in a shader
    /// call (Surface "x" "Ksub" 0): kept as Float numbers or Strings for the
    /// shader's own declaration to type, as PRMan does.
    bool declared = true;

    /// Numbers per element = param_type_components(type) * array_size.
    int element_size() const;
    /// Number of elements given (numbers.size() / element_size(), or strings.size()).
    std::size_t element_count() const;
};

/// A parameter list with typed getters. Getters return the default when the
/// parameter is absent and throw ValueError when it has the wrong type or
/// too few values.
class ParamList {
public:
    std::vector<Param> items;

    const Param* find(std::string_view name) const;
    bool has(std::string_view name) const { return find(name) != nullptr; }
    double get_float(std::string_view name, double fallback) const;
    int get_int(std::string_view name, int fallback) const; ///< float or integer
    std::string get_string(std::string_view name, const std::string& fallback) const;
    /// color, point, vector, normal or 3 floats.
    glm::dvec3 get_vec3(std::string_view name, const glm::dvec3& fallback) const;
    /// Adds or replaces a parameter.
    void set(Param p);
};

/// A shader call (`Surface`, `LightSource`, ...) with the transform in effect.
struct ShaderRef {
    std::string name;
    ParamList params;
    Matrix4 shader_to_world{1.0}; ///< the "shader" space: CTM at the call
    std::string source;           ///< "file.rib:12" of the call
};

/// `Shader "name" "handle" params`: an RSL 2.0 co-shader that the surface,
/// displacement, light and volume shaders of the primitives in its scope
/// reach by its handle (getshader, getshaders).
struct CoshaderRef {
    std::string handle;
    ShaderRef shader;
};

/// A spline basis for bicubic patches: 4x4 matrix (in RenderMan's row-vector
/// layout, loaded as documented above) and its step. Default-constructed, it
/// is the power basis; Attributes start with Bezier, the RI default.
struct Basis {
    Matrix4 matrix{1.0};
    int step = 4;
    std::string name = "power";
};
/// The named bases of the RI spec: bezier, b-spline (also "bspline"),
/// catmull-rom (also "catmullrom"), hermite, power. nullopt if unknown.
std::optional<Basis> named_basis(std::string_view name);

/// `TrimCurve` loops: non-uniform rational B-spline curves in the (u, v)
/// parameter space of the NuPatches they trim, in RIB order (every array
/// concatenated over the curves, as RiTrimCurve takes them).
struct TrimCurves {
    std::vector<int> ncurves;     ///< curves per loop
    std::vector<int> order;       ///< per curve
    std::vector<double> knot;     ///< n + order per curve
    std::vector<double> min, max; ///< parameter range per curve
    std::vector<int> n;           ///< control points per curve
    std::vector<double> u, v, w;  ///< homogeneous control points
};

/// The attribute state of a primitive or light (shared by many primitives).
struct Attributes {
    glm::dvec3 color{1.0};           ///< Color (Cs)
    glm::dvec3 opacity{1.0};         ///< Opacity (Os)
    int sides = 2;                   ///< Sides 1|2
    bool orientation_inside = false; ///< Orientation "inside" (after ReverseOrientation)
    double shading_rate = 1.0;
    std::string shading_interpolation = "constant";
    std::optional<ShaderRef> surface;      ///< Surface
    std::optional<ShaderRef> displacement; ///< Displacement
    /// Atmosphere: the volume shader run on camera rays between the eye and
    /// the surface they hit; Interior and Exterior: the volume shaders of
    /// the inside and the outside of the object, run on traced rays.
    /// Unset without the request, or after `"null"` / `""`.
    std::optional<ShaderRef> atmosphere, interior, exterior;
    std::vector<int> lights_on; ///< indices into Scene::lights, ascending
    /// The co-shaders in effect, in declaration order (a `Shader` with a
    /// handle already here replaces that one).
    std::vector<CoshaderRef> coshaders;
    /// Every `Attribute "group" params`, by group ("cull", "dice", "identifier"...).
    std::map<std::string, ParamList> groups;
    Basis u_basis = *named_basis("bezier");
    Basis v_basis = *named_basis("bezier");
    /// The current TrimCurve (none: untrimmed NuPatches).
    std::shared_ptr<const TrimCurves> trim_curves;
    /// `Attribute "identifier" "name"` if given, else "".
    std::string name() const;
    /// Whether `Attribute "visibility" kind` ("camera", "transmission",
    /// "diffuse"...) leaves the object visible: only an explicit 0 (or
    /// "transparent") turns it off, so objects cast shadows by default.
    /// "diffuse" and "specular" fall back to PRMan 12's "trace".
    bool visible_to(const char* kind) const;
};

/// The geometric primitives the scene layer knows.
enum class PrimitiveKind {
    Polygon,
    GeneralPolygon,
    PointsPolygons,
    PointsGeneralPolygons,
    SubdivisionMesh,
    Sphere,
    Cylinder,
    Cone,
    Disk,
    Torus,
    Hyperboloid,
    Paraboloid,
    Patch,
    PatchMesh,
    Teapot,
    Points,
    Curves,
    NuPatch,
    Blobby
};
/// The RIB request of a kind ("PointsPolygons", "Sphere", ...).
const char* primitive_kind_name(PrimitiveKind kind);

struct PrimitiveMotion;

/// One primitive as the RIB gave it, in its object space.
struct Primitive {
    PrimitiveKind kind = PrimitiveKind::Polygon;
    /// Positional numbers: quadric arguments in RIB order (Sphere: radius zmin
    /// zmax thetamax; Cylinder: radius zmin zmax thetamax; Cone: height radius
    /// thetamax; Disk: height radius thetamax; Torus: major minor phimin phimax
    /// thetamax; Hyperboloid: x1 y1 z1 x2 y2 z2 thetamax; Paraboloid: rmax zmin
    /// zmax thetamax). Angles in degrees, as in the RIB.
    std::vector<double> args;
    /// Topology. GeneralPolygon: nverts per loop. PointsPolygons: nverts per
    /// face + verts. PointsGeneralPolygons: nloops per face, nverts per loop,
    /// verts. SubdivisionMesh: nverts per face + verts.
    std::vector<int> nloops;
    std::vector<int> nverts;
    std::vector<int> verts;
    /// Patch / PatchMesh type ("bicubic" or "bilinear"); SubdivisionMesh
    /// scheme; Curves type ("linear" or "cubic"). Curves: nverts holds the
    /// vertices per curve and vwrap whether they are periodic.
    std::string type;
    /// PatchMesh: vertex counts and wrap modes ("periodic" -> true).
    /// NuPatch: control points in u and v.
    int nu = 0;
    int nv = 0;
    /// NuPatch: order, knot vector (nu + uorder knots) and parameter range
    /// in u and in v. Its "Pw" stays homogeneous.
    int uorder = 0, vorder = 0;
    std::vector<double> uknot, vknot;
    double umin = 0.0, umax = 1.0, vmin = 0.0, vmax = 1.0;
    bool uwrap = false;
    bool vwrap = false;
    /// Blobby: nu is nleaf, verts the code array, args the float array and
    /// tags the string array, as RIB gives them (blobby.h decodes them).
    /// SubdivisionMesh tags: names, nargs (2 per tag: ints, floats), intargs, floatargs.
    std::vector<std::string> tags;
    std::vector<int> tag_nargs;
    std::vector<int> tag_intargs;
    std::vector<double> tag_floatargs;
    /// "P", optional "N", "Cs", and anything else given.
    ParamList params;
    Matrix4 object_to_world{1.0};
    std::shared_ptr<const Attributes> attributes;
    std::string source; ///< "file.rib:12" of the statement
    /// Motion blur (MotionBegin): null for a primitive that does not move.
    /// Its own args, params and object_to_world are those of the first time.
    std::shared_ptr<const PrimitiveMotion> motion;
};

/// How a primitive moves (RIB MotionBegin blocks): its transform and its
/// shape at a few times each (increasing), linear in between and held
/// before the first and after the last (RISpec 3.2 section 4.3).
struct PrimitiveMotion {
    /// Times of `transforms`; empty: object_to_world at every time.
    std::vector<double> transform_times;
    std::vector<Matrix4> transforms; ///< object_to_world at each transform time
    /// Times of the shapes; empty: the primitive's own shape at every time.
    std::vector<double> shape_times;
    /// Per shape time: the positional numbers and the parameter list ([0]
    /// is the primitive's own). Same topology at every time.
    std::vector<std::vector<double>> shape_args;
    std::vector<ParamList> shape_params;

    /// Every time anything is given at (sorted, distinct).
    std::vector<double> times() const;
};

/// The primitive as it is at `time`: transform and shape interpolated
/// linearly between the motion samples around it (the numbers of every
/// parameter that has as many at both; others from the earlier sample),
/// without motion. A primitive that does not move is returned as it is.
Primitive primitive_at(const Primitive& prim, double time);

/// Linear interpolation of `keys` at `time` (held outside `times`).
Matrix4 matrix_at(const std::vector<double>& times, const std::vector<Matrix4>& keys,
                  double time);

/// A primitive's attributes (RI defaults for a primitive built without any).
const Attributes& attributes_of(const Primitive& prim);

/// How many values each storage class carries on a primitive: constant 1,
/// uniform one per face, varying and vertex one per (varying or control)
/// point, facevarying one per face corner, facevertex one per face control
/// point.
struct ClassCounts {
    std::size_t uniform = 1;
    std::size_t varying = 4;
    std::size_t vertex = 4;
    std::size_t facevarying = 4;
    std::size_t facevertex = 4;

    /// The number of values a parameter of storage class c must have.
    std::size_t of(ParamClass c) const;
};

/// A light source instance.
struct LightInstance {
    ShaderRef shader;   ///< ambientlight, distantlight, pointlight, spotlight, *_rts...
    std::string handle; ///< the RIB handle (integer sequence number or string)
    bool area = false;  ///< declared with AreaLightSource
};

/// `Display name type mode params`.
struct DisplaySpec {
    std::string name;
    std::string type; ///< "file", "openexr", "tiff", "png", "it", "framebuffer"...
    std::string mode; ///< "rgba", "rgb", "_radiance_t", "Ci,a"...
    ParamList params;
    bool additional = false; ///< the name started with '+'
    std::string where;       ///< "scene.rib:9" (empty when not read from a RIB)
};

/// The camera and image options in effect at WorldBegin.
struct Camera {
    Matrix4 world_to_camera{1.0};
    bool perspective = false; ///< RI default projection is orthographic
    double fov = 90.0;        ///< degrees, perspective only
    int xres = 640;
    int yres = 480;
    double pixel_aspect = 1.0;
    /// ScreenWindow left right bottom top; nullopt = RI default from the frame aspect.
    std::optional<std::array<double, 4>> screen_window;
    double near_clip = 1e-10; ///< Clipping hither
    double far_clip = 1e30;   ///< Clipping yon
    /// DepthOfField fstop focallength focaldistance (camera-space units):
    /// a thin lens of radius focallength / (2 fstop) focused at
    /// focaldistance. fstop = infinity (the default, or `DepthOfField`
    /// without arguments) is the pinhole camera.
    double fstop = std::numeric_limits<double>::infinity();
    double focal_length = 0.0;
    double focal_distance = 0.0;
    /// Shutter open close: the times camera samples spread over (equal:
    /// no motion blur, everything as it is at shutter_open).
    double shutter_open = 0.0;
    double shutter_close = 0.0;
    /// A moving camera (MotionBegin around camera transformations):
    /// world_to_camera at each of motion_times; empty when it stands still
    /// (world_to_camera is the first).
    std::vector<double> motion_times;
    std::vector<Matrix4> motion_world_to_camera;

    /// Whether samples spread over a shutter interval.
    bool motion_blur() const { return shutter_close > shutter_open; }

    /// Where each part was set, as errors name it ("scene.rib:3: ScreenWindow");
    /// empty when the RI default is in effect.
    struct Sources {
        std::string format;         ///< Format
        std::string frame_aspect;   ///< FrameAspectRatio
        std::string screen_window;  ///< ScreenWindow
        std::string projection;     ///< Projection
        std::string clipping;       ///< Clipping
        std::string depth_of_field; ///< DepthOfField
        std::string shutter;        ///< Shutter
        /// WorldBegin: the transformation in effect there is world_to_camera.
        std::string world_begin;
    };
    Sources sources;

    /// Whether DepthOfField gives the camera a lens (finite fstop).
    bool depth_of_field() const { return std::isfinite(fstop) && focal_length > 0.0; }
    /// The lens radius focallength / (2 fstop) in camera-space units (0: pinhole).
    double lens_radius() const {
        return depth_of_field() ? focal_length / (2.0 * fstop) : 0.0;
    }

    /// The screen window in effect (given or default).
    std::array<double, 4> resolved_screen_window() const;
    /// RenderMan's world-to-NDC matrix: x, y in [0, 1] over the screen
    /// window, y down (what bake3d and EXR headers record).
    Matrix4 world_to_ndc() const;
    /// Length in world (camera) units of one raster pixel at camera-space
    /// distance `distance` from the eye (perspective) or anywhere (orthographic).
    double pixel_size_at(double distance) const;
};

/// The camera's rays in world space: the ray through each raster point,
/// through a point of the lens with DepthOfField (camera.cpp). For a camera
/// that passed check_camera.
class CameraProjection {
public:
    explicit CameraProjection(const Camera& camera);

    /// A ray in world space: origin, unit direction, its length per unit of
    /// camera z (the depth of a point at distance t is t / units) and the
    /// interval [hither, yon] along it (yon >= 1e30: infinity).
    struct Ray {
        glm::dvec3 origin{0.0};
        glm::dvec3 direction{0.0, 0.0, 1.0};
        double units = 1.0;
        double tnear = 0.0;
        double tfar = 0.0;
    };
    /// The ray through raster point (x, y) (pixels, y down). With
    /// DepthOfField it starts at `lens` (a point of the unit disk) times the
    /// lens radius, in the plane z = 0 of camera space, and goes through the
    /// point where the pinhole ray meets the focal plane z = focaldistance
    /// (orthographic cameras: the same, around the pinhole ray's origin).
    Ray ray(double x, double y, const glm::dvec2& lens) const;

private:
    Camera m_cam;
    std::array<double, 4> m_window{};
    double m_tan_half = 1.0;
    Matrix4 m_to_world{1.0};
    bool m_affine = true;       ///< m_to_world's last row is (0, 0, 0, 1)
    double m_lens_radius = 0.0; ///< DepthOfField (camera units); 0: pinhole
};

/// Checks that a camera defines camera space and can size micropolygons
/// (camera.cpp): an image with pixels, a finite screen window with area, a
/// field of view in (0, 180) degrees, 0 <= hither < yon, a lens with fstop >
/// 0 and focaldistance > focallength, a world-to-camera transform that is
/// finite and invertible, and an eye within kMaxWorldCoordinate of the world
/// origin. With `rays` (render), also that every camera ray (over the
/// screen window and the lens) starts within that range and has a direction.
/// Throws ValueError naming the RIB statement responsible
/// ("scene.rib:9: WorldBegin: the camera transform ... is singular ...").
void check_camera(const Camera& camera, bool rays = true);

/// `PixelFilter name xwidth ywidth`: the reconstruction filter (RISpec 3.2
/// appendix E), its support xwidth by ywidth pixels. Names: box, triangle,
/// catmull-rom, gaussian, sinc.
struct PixelFilterSpec {
    std::string name = "gaussian";
    double xwidth = 2.0;
    double ywidth = 2.0;
};

/// `Quantize "rgba" one min max ditheramplitude` (and a Display's
/// `"quantize" [zero one min max]` / `"dither" [amplitude]`): an integer
/// output value is round(zero + one * v + dither * r), r in [-1, 1), clamped
/// to [min, max]. one = 0 asks for float output.
struct QuantizeSpec {
    double zero = 0.0;
    double one = 255.0;
    double min = 0.0;
    double max = 255.0;
    double dither = 0.5;
};

/// Image and render options.
struct RenderOptions {
    Camera camera;
    int pixel_samples[2] = {2, 2};
    std::vector<DisplaySpec> displays;
    /// `DisplayChannel "color _radiance_t"` declarations: name -> type string.
    std::vector<std::pair<std::string, std::string>> display_channels;
    /// Every `Option "group" params`.
    std::map<std::string, ParamList> groups;
    /// `Option "searchpath" "kind" ["a:b"]` by kind ("shader", "texture",
    /// "archive", "procedural"...): the folders in order, "&" replaced by the
    /// kind's previous path when the Option was read, "@" kept (the standard
    /// place: the standard shaders for "shader", none for the others).
    /// Relative folders are relative to the working folder. Kinds not set
    /// take search_path()'s defaults.
    std::map<std::string, std::vector<std::string>> search_paths;
    std::string hider;
    PixelFilterSpec pixel_filter; ///< PixelFilter (default gaussian 2 2)
    /// `Imager "name" params` (an option): the imager shader run on every
    /// final pixel; unset without one, or after `Imager "null"` / `""`.
    std::optional<ShaderRef> imager;
    /// Exposure gain gamma: colour = (gain * colour)^(1/gamma) when written.
    double exposure_gain = 1.0;
    double exposure_gamma = 1.0;
    /// Quantize "rgba"/"rgb" (PRMan's default 255 0 255 0.5); nullopt: the
    /// format's default. Quantize "z" is accepted and ignored (Z is float).
    std::optional<QuantizeSpec> quantize;
    std::optional<int> frame; ///< number of the FrameBegin block read, if any
};

/// A whole scene (one frame).
/// A texture-making request of the RIB (MakeTexture, MakeLatLongEnvironment,
/// MakeShadow, MakeCubeFaceEnvironment). Requests inside the frame read run
/// before anything is shaded; requests between frames belong to the frames
/// on either side: the ones before FrameBegin n run before frame n, the
/// ones after its FrameEnd (up to the next FrameBegin) after frame n is
/// written (`after_frame`), so that a zfile a frame renders can be made
/// into the shadow map the next frame reads (docs/scene.md, "Frames").
struct MakeRequest {
    std::string kind;   ///< the RIB request
    std::string input;  ///< the picture (zfile), found along the texture search path
    std::string output; ///< the texture, relative to the working folder
    /// MakeCubeFaceEnvironment: the six pictures px nx py ny pz nz (input is
    /// the first).
    std::vector<std::string> faces;
    double fov = 90.0; ///< MakeCubeFaceEnvironment: each picture's field of view
    std::string swrap = "black", twrap = "black", filter = "box";
    double swidth = 1.0, twidth = 1.0;
    ParamList params;
    std::string source;       ///< "file.rib:3"
    bool after_frame = false; ///< run after the frame is rendered
};

struct Scene {
    RenderOptions options;
    std::vector<Primitive> primitives;
    std::vector<LightInstance> lights;
    /// CoordinateSystem name -> space-to-world.
    std::map<std::string, Matrix4> coordinate_systems;
    /// Non-fatal problems met while reading (unknown statements...), each
    /// "file.rib:12: ...", counted by kind (a few of each kind kept); the
    /// tool prints them as warnings.
    Warnings warnings;
    std::string path; ///< the RIB file it was read from
    /// Every file the scene was read from: the RIB (when read from a file),
    /// then each ReadArchive / DelayedReadArchive file and OBJ mesh once, in
    /// first-read order. The inputs of `-newer 1`.
    std::vector<std::string> sources;
    /// The Make* requests of the frame read, in RIB order (MakeRequest says
    /// which run before and which after the frame).
    std::vector<MakeRequest> makes;
    /// The numbers of every FrameBegin of the file, in order (the one read
    /// and the skipped ones).
    std::vector<int> frame_numbers;
    /// How each of `sources` was named, for messages: "the scene file",
    /// "ReadArchive \"cube.obj\" at scene.rib:3".
    std::vector<std::string> source_uses;
    /// WorldBegin blocks read (a file with none is an archive, not a scene).
    int worlds = 0;
};

/// The search path of `kind` ("shader", "texture", "archive",
/// "procedural"): the scene's Option "searchpath", else the default: the
/// working folder ".", the RIB's folder (when it is another), and for
/// shaders "@" (the standard shaders). "@" entries stay for the caller.
std::vector<std::string> search_path(const Scene& scene, const std::string& kind);

/// The default search path of `kind` for a scene read from `rib_path`.
std::vector<std::string> default_search_path(const std::string& rib_path,
                                             const std::string& kind);

/// `name` found along `path`: an absolute name as it is; a relative one
/// joined to each folder in order ("." leaves it as it is; "@" entries are
/// skipped), the first that exists. nullopt when none does.
std::optional<std::string> find_on_search_path(const std::vector<std::string>& path,
                                               const std::string& name);

/// "a:b:@", for messages.
std::string search_path_text(const std::vector<std::string>& path);

/// The frame a job works on: `requested` (the tools' -frame) when given, else
/// the scene's own (the FrameBegin block it read), else none.
inline std::optional<int> job_frame(const Scene& scene, std::optional<int> requested) {
    return requested ? requested : scene.options.frame;
}

} // namespace sss
