// Copyright The sss Authors
// SPDX-License-Identifier: Apache-2.0
#pragma once
/// \file program.h
/// Module rsl: the RenderMan Shading Language compiler, in phases as OSL's
/// (preprocess.h; lexer, parser, the code generator by phase: types,
/// expressions, calls, statements; compiler.h), compiled shaders (this file)
/// and their `.slo` files, the built-in functions' signatures (builtins.h)
/// and the shader search path (shader_library.h). It knows nothing of
/// scenes or renderers: the `shader` tool needs nothing else.
/// May use: util.
///
/// A compiled shader, as the compiler produces it and a `.slo` file stores
/// it: a table of typed symbols and a list of operations over them, with
/// structured control flow (each `if`, loop, `illuminance`... op names the
/// op ranges of its parts), in the manner of OSL's `.oso` files. User
/// functions are inlined by the compiler (RSL forbids recursion), so a
/// Program has no calls besides built-ins.
///
/// Operations (`Op::name`; the result, when there is one, is args[0]):
///  - `assign d s`: d = s; s may be a float for a triple (replicated) or a
///    matrix (s * identity), or any of point/vector/normal for another.
///  - `neg d a`, `add d a b`, `sub`, `mul`, `div`: component by component, a
///    float operand replicated; `mul` of two matrices is the matrix product,
///    `div` of two matrices is a * inverse(b); float * matrix scales.
///  - `dot d a b` (RSL `.`), `cross d a b` (RSL `^`).
///  - `eq ne lt le gt ge d a b`, `and or d a b`, `not d a`: d is a float 0/1.
///  - `aref d array index`, `aassign array index s`: array element (index
///    rounded down, bounds-checked at run time against the array's length,
///    a resizable array's current one).
///  - Resizable arrays (type array kResizableArray, locals only; one length
///    for the whole batch, starting at 0): `arraylength d a` (d = the
///    length, uniform; a may be any array), `resize a n` (n uniform: the
///    first elements kept, new ones 0), `reserve a n` (a capacity hint),
///    `push a v` (length + 1, v stored at the running points), `pop d a`
///    (d = the last element, then length - 1; writes d and a). resize, reserve
///    and push write a (bit 0). Lengths over kMaxArrayLength are run-time
///    errors.
///  - `construct d [space] x y z` (color/point/vector/normal from three
///    floats) or `construct d [space] m00 ... m33` (matrix, row-major) or
///    `construct d space f` (matrix space f*I): the optional space (a string
///    symbol) converts the value into the current space, or from a colour
///    space into rgb.
///  - `cast d space s`: s (a triple or matrix) taken as being in `space`,
///    converted to the current space (or colour space -> rgb).
///  - `if c`: the then-part is ops [i+1, jump[0]), the else-part
///    [jump[0], jump[1]); c is a float.
///  - `loop c`: init [i+1, jump[0]), condition [jump[0], jump[1]) which sets
///    c, body [jump[1], jump[2]), step [jump[2], jump[3]). `while` and `for`
///    both become `loop`.
///  - `break` / `continue` with `level` (1 = innermost loop).
///  - `block`: ops [i+1, jump[0]) form an inlined function body; `return`
///    inside it ends it for the running points (the function's result was
///    assigned by the op before). A `return` outside any `block` ends the
///    shader for those points.
///  - `illuminance cat p axis angle ("name" value)...`: body [i+1, jump[0])
///    run once per light (cat is "" without a category; no axis/angle: angle
///    = PI and axis 0 means the whole sphere). Options: "lightcache"
///    "refresh"/"reuse", "send:light:NAME" value (read), "light:NAME" var
///    (written each iteration: its bit in `writes`).
///  - `illuminate p axis angle` / `solar axis angle` (light shaders): body
///    [i+1, jump[0]); without axis/angle the angle symbol holds -1.
///  - `gather cat p dir angle samples ("name" value)...`: ray tracing
///    (engine_raytrace.cpp): the hit body is ops [i+1, jump[0]), the else
///    body [jump[0], jump[1]), each run once per sample for the points whose
///    ray hit / missed. cat is "" when the source gave "" (also
///    "illuminance", "environment"); p a point, dir a vector, angle and
///    samples floats. Option values whose name has a ':' prefix
///    ("surface:<var>", "ray:length", "ray:direction", "ray:origin",
///    "environment:color", "environment:direction") are variables the op
///    writes (their bits in `writes`; no other bit is set); the others are
///    read. Not a loop level for break/continue.
///  - RSL 2.0 co-shaders (a `shader` value is a handle, 0 null):
///    `getshader d name` / `getlight d name` (d: the co-shader / light whose
///    RIB handle is the string name, or null), `getshaders a ("category"
///    cat)...` / `getlights a ...` (a: a resizable shader array, written),
///    `getvar d h name [var]` (d = 1 when the shader has a parameter or
///    member variable name; var, written, receives its value),
///    `hasmethod d h name` (d = 1 when shader h has a public method name),
///    `callmethod d h name args...` (runs method name of shader h: args that
///    are written (their bits in `writes`) are passed by reference and
///    receive the method's outputs; d receives the result when bit 0 is set).
///  - anything else is a built-in function call (builtins.h lists every
///    name and its overloads); token-value lists follow the fixed arguments
///    as (string, value) symbol pairs. `texture`, `environment` and `shadow`
///    always carry the channel (a float symbol) as their second argument.
///
/// What the compiler emits, in more detail (the front end's conventions):
///  - Built-in calls: args[0] is the result unless the overload returns void
///    (`fresnel`, `setxcomp`, `printf`...: then the arguments start at
///    args[0]); the arguments follow in source order, converted to the
///    overload's types (a float for a triple, point/vector/normal among
///    themselves), except output arguments, which are the variables
///    themselves, with their bits set in `writes` (texture3d's token values
///    too). `texture("f"[2], s, t)` is `texture r "f" 2 s t`; without a
///    subscript the channel is the constant 0.
///  - Every op that computes a value writes args[0] (writes == 1): assign,
///    arithmetic, comparisons, aref, construct, cast; `aassign` writes its
///    array (args[0]). Control ops (if, loop, block, illuminance...,
///    break, continue, return) write nothing and have writes == 0.
///  - `eq`/`ne` get operands of one type (a float compared with a triple is
///    first assigned to a triple temp); `lt le gt ge and or not` take floats.
///    A condition that is a triple is compared `ne` against 0.
///  - `?:` becomes an `if` whose two parts assign a temp.
///  - `construct`: args [d, x, y, z], [d, space, x, y, z], [d, 16 floats],
///    [d, space, 16 floats] or [d, space, f] (matrix); `point "sp" 1` is
///    `construct d sp f f f`. Triples of constants without a space are
///    constants, not ops.
///  - `return` in the body of the shader (outside any block) ends the shader
///    for the running points; in an inlined function it ends the block, the
///    result (symbol "<function>::result@<n>") having been assigned just
///    before. A void function's `return` has no assignment before it.
///  - `illuminance`: all four arguments are always present: category ""
///    when absent; axis the constant vector (0,0,0) and angle PI when
///    absent; then the options it supports (names constant strings; others
///    are dropped with a warning). `illuminate p axis angle` / `solar axis
///    angle`: the constant vector (0,0,0) and -1 when absent.
///  - A resizable local's declaration emits `resize a n` (n: the number of
///    `{...}` values, 0 without) and then an `aassign` per value; a fixed
///    array's `arraylength` is a constant.
///  - `gather`: the five fixed arguments are always present; output token
///    names must be constant strings and their values variables (a
///    "primitive:" output is a compile error); the bodies count as being
///    under a varying condition and the outputs are varying. occlusion()
///    and indirectdiffuse() also write the values of their
///    "environmentcolor", "environmentdir" and "occlusion" options (which
///    must be variables). An op has at most 64 arguments (`writes` is 64
///    bits): a call with more is a compile error.
///  - `break`/`continue` count `loop` ops only (not illuminance, gather), within
///    the enclosing block (a function cannot break its caller's loop).
///  - Symbols: temps are "$t<n>", constants "$c<n>" (deduplicated), locals of
///    the body keep their name ("x", or "x@2" when a name is reused in
///    another scope), inlined functions' parameters and locals are
///    "<function>::<name>@<n>" (n: the inlining). A by-reference parameter
///    whose argument is a variable of the same type (always for output and
///    array parameters) is that variable: no symbol of its own.
///  - A parameter whose default is constant has its value in
///    numbers/strings and init_begin == init_end == -1; otherwise its default
///    ops are [init_begin, init_end), before body_begin, in declaration order.
///  - Class shaders (RSL 2.0 `class`): member variables are locals of the
///    program named as declared, initialised by ops [body_begin, init_end);
///    each public method (and each pipeline method: construct, begin,
///    displacement, opacity, surface, prelighting, lighting, postlighting,
///    light, volume) follows as a `block` of its own (Program::methods),
///    whose parameters are symbols "<method>::<name>@<n>" (varying unless
///    declared uniform) or, for a pipeline method, the globals they name.
///    Calls between methods of the class are inlined like functions.
///  - Symbol::varying is final: locals declared without `uniform`/`varying`
///    are uniform when every assignment to them is uniform and not under a
///    varying condition (nor after a varying break/continue/return).

#include <array>
#include <cstdint>
#include <iosfwd>
#include <string>
#include <vector>

namespace sss {

/// The basic types of RSL.
enum class ShadingType : uint8_t {
    Void,
    Float,
    Color,
    Point,
    Vector,
    Normal,
    Matrix,
    String,
    /// RSL 2.0 co-shader handle (`shader s = getshader("name")`): one float,
    /// an index into the shading context's table of shader objects (0 is
    /// `null`). Only locals, member variables and temporaries have it.
    Shader
};

/// RSL spelling ("float", "color", ...).
const char* shading_type_name(ShadingType t);
/// Floats per value: 1 for float, string (a string is a table index) and
/// shader (a handle), 3 for the triples, 16 for matrix, 0 for void.
int shading_type_floats(ShadingType t);
/// point, vector or normal.
bool is_point_like(ShadingType t);
/// color, point, vector or normal.
bool is_triple(ShadingType t);

/// `TypeSpec::array` of a resizable array (`float a[]`, PRMan 13.5's
/// dynamic arrays): its length is set at run time (resize, push, pop).
constexpr int kResizableArray = -1;
/// The longest array: fixed lengths and the run-time length of resizable ones.
constexpr int kMaxArrayLength = 1000000;

/// A type with an optional array length.
struct TypeSpec {
    ShadingType type = ShadingType::Float;
    int array = 0; ///< 0: not an array; > 0: fixed length; kResizableArray

    bool is_array() const { return array != 0; }
    /// A resizable array (locals and temporaries only).
    bool is_resizable() const { return array < 0; }
    /// Floats per element times elements (0 for a resizable array, whose
    /// storage the engine keeps apart).
    int floats() const {
        return array < 0 ? 0 : shading_type_floats(type) * (array > 0 ? array : 1);
    }
    bool operator==(const TypeSpec&) const = default;
};
/// "float", "color[3]", "float[]" (resizable), ...
std::string type_spec_name(const TypeSpec& t);

/// The kinds of shaders. `Shader` is an RSL 2.0 class without any pipeline
/// method (a co-shader: its methods are called by other shaders only).
enum class ShaderKind : uint8_t { Surface, Displacement, Light, Volume, Imager, Shader };
const char* shader_kind_name(ShaderKind k);

/// What a symbol is.
enum class SymbolKind : uint8_t {
    Param,       ///< shader parameter (read-only in the body)
    OutputParam, ///< `output` shader parameter
    Global,      ///< P, N, Ci, ... (bound by the engine)
    Local,       ///< a variable of the body or of an inlined function
    Temp,        ///< compiler temporary
    Const        ///< literal (value in `numbers` / `strings`)
};

/// One symbol of a Program.
struct Symbol {
    std::string name; ///< unique within the program (inlined locals are renamed)
    TypeSpec type;
    bool varying = false; ///< false: one value for the whole batch
    SymbolKind kind = SymbolKind::Temp;
    /// Const values; also a parameter's default when it is a constant
    /// expression (then init_begin == init_end).
    std::vector<float> numbers;
    std::vector<std::string> strings;
    /// Parameters: ops [init_begin, init_end) compute the default into the
    /// symbol (empty when `numbers`/`strings` hold it).
    int init_begin = -1;
    int init_end = -1;
};

/// Where an op came from, for run-time messages.
struct SourceLocation {
    int file = -1; ///< index into Program::files
    int line = 0;
    int column = 0;
};

/// One operation.
struct Op {
    std::string name;
    std::vector<int> args;                   ///< symbol indices
    std::array<int, 4> jump{-1, -1, -1, -1}; ///< op indices (control flow)
    int level = 0;                           ///< break / continue
    /// Bit i set: args[i] is written by the op (results and output args).
    uint64_t writes = 0;
    SourceLocation where;
};

/// A method of a class shader (RSL 2.0 `class`), as other shaders call it
/// (`s->name(args)`) and as the renderer runs the pipeline methods.
struct Method {
    std::string name;
    bool is_public = true;
    /// Ops [begin, end): a `block` op holding the body (jump[0] == end).
    int begin = 0;
    int end = 0;
    int result = -1;         ///< symbol receiving the returned value; -1: void
    std::vector<int> params; ///< parameter symbols in order
    /// Bit k: params[k] is an output (copied back to the caller's argument).
    uint64_t outputs = 0;
};

/// The methods a class shader runs, in order, when it runs as `kind`.
struct Pipeline {
    ShaderKind kind = ShaderKind::Surface;
    std::vector<int> methods; ///< indices into Program::methods
};

/// A compiled shader.
struct Program {
    ShaderKind kind = ShaderKind::Surface;
    std::string name; ///< the shader's name (the .slo's stem)
    std::vector<Symbol> symbols;
    std::vector<Op> ops;            ///< parameter defaults first, then the body
    int body_begin = 0;             ///< first op of the body
    std::vector<std::string> files; ///< source files (SourceLocation::file)
    std::string source_path;        ///< the .sl it was compiled from

    /// Class shaders (RSL 2.0): ops [body_begin, init_end) initialise the
    /// member variables; the methods follow. -1 for a classic shader, whose
    /// body is ops [body_begin, ops.size()).
    int init_end = -1;
    std::vector<Method> methods;     ///< class shaders: the public methods
    std::vector<Pipeline> pipelines; ///< class shaders: one per kind it runs as

    bool is_class() const { return init_end >= 0; }
    /// Whether the shader can run as `k`: its kind, or one of a class's
    /// pipelines (a class with displacement and surface methods is both).
    bool runs_as(ShaderKind k) const;
    /// The pipeline of kind `k`, or null.
    const Pipeline* pipeline(ShaderKind k) const;
    /// Index of the method `name`, or -1.
    int find_method(const std::string& name) const;
    /// Index of the symbol `name`, or -1.
    int find(const std::string& name) const;
    /// Parameter symbol indices in declaration order.
    std::vector<int> parameters() const;
};

/// A .slo file that cannot be read.
/// (Thrown as sss::ValueError with the file name and line.)
///
/// Writes `program` in the .slo text format (docs/shading.md, "Compiled
/// shaders"): a versioned header, the symbols and the ops.
void write_program(const Program& program, std::ostream& out);
/// Reads a .slo written by write_program; `path` names it in errors.
/// Validates everything (symbol indices, jump ranges, types) so that a
/// damaged file is an error, never a crash in the engine.
Program read_program(std::istream& in, const std::string& path);
/// read_program from a file.
Program read_program_file(const std::string& path);
/// write_program to a file, atomically (util/atomic_output.h). Throws IoError.
/// (An addition of the front end, for the `shader` tool.)
void write_program_file(const Program& program, const std::string& path);

} // namespace sss
