# Copyright The sss Authors
# SPDX-License-Identifier: Apache-2.0
"""sss: point clouds, subsurface diffusion and brick maps from Python.

The binding of the sss library (docs/python.md). Point clouds are dicts of
numpy arrays (:class:`Cloud`); the diffusion takes ptfilter's options as
keyword arguments and gives the same numbers as the ``ptfilter`` executable;
brick maps and point clouds are looked up (texture3d) many points at a time.
Long calls release the GIL and report progress to a callback; errors are
:class:`Error` subclasses carrying the library's message, which are also the
builtin exceptions a caller catches anyway (OSError, FileNotFoundError,
ValueError). numpy is needed for arrays; typing stubs come with the package.

Example::

    import sss
    cloud = sss.read_cloud("bake.ptc")
    out = sss.ssdiffusion(cloud, material="skin1", unitlength=0.1)
    sss.write_cloud("diffused.ptc", out)
    sss.make_brickmap(["diffused.ptc"], "diffused.bkm", maxerror=0.002)
    values = sss.BrickMap("diffused.bkm").lookup(out["P"], "_ssdiffusion",
                                                 normals=out["N"])
"""

import numbers as _numbers
import os as _os
import sys as _sys
import warnings as _warnings

from . import _sss
from ._errors import (
    Error,
    FileNotFoundError,
    FormatError,
    IoError,
    LimitError,
    OutOfMemoryError,
    UsageError,
    ValueError,
    _Brief,
)
from ._sss import __version__

# sss.ValueError and sss.FileNotFoundError derive from the builtins of the
# same names; they are left out of __all__ so that `from sss import *` does
# not hide the builtins.
__all__ = [
    "BrickMap",
    "Cloud",
    "Error",
    "FormatError",
    "IoError",
    "LimitError",
    "OutOfMemoryError",
    "PointCloudLookup",
    "UsageError",
    "__version__",
    "expand_frame_pattern",
    "has_frame_pattern",
    "isa_names",
    "make_brickmap",
    "ptfilter",
    "read_cloud",
    "ssdiffusion",
    "write_cloud",
]


def __dir__():
    # The API only: the imports and helpers behind it are not part of it.
    return sorted(__all__ + ["FileNotFoundError", "ValueError", "__all__", "__doc__",
                             "__file__", "__name__", "__path__"])


def _numpy():
    """numpy, which every call that takes or returns arrays needs; a clear
    ImportError where this interpreter has none."""
    try:
        import numpy
    except ImportError as e:
        raise ImportError(
            "sss needs numpy for point clouds and lookups (arrays), and this Python "
            f"({_sys.executable}, {_sys.version.split()[0]}) has none: install numpy "
            "for it (pip install numpy; Debian's python3: apt-get install "
            "python3-numpy). ptfilter(), make_brickmap() from files, BrickMap's info "
            "and the frame patterns work without it.") from e
    return numpy


_GEOMETRY = ("P", "N", "radius")
_CLOUD_EXTENSIONS = (".ptc", ".ply")


class Cloud(dict, metaclass=_Brief):
    """A point cloud: a dict of numpy float32 arrays, one row per point.

    Keys: ``"P"`` (N, 3) positions, ``"N"`` (N, 3) normals (zero: no normal),
    ``"radius"`` (N,), then every channel in file order: ``float`` channels
    (N,), ``color``/``point``/``vector``/``normal`` (N, 3), ``matrix``
    (N, 4, 4). Only ``"P"`` is required when writing; ``N`` and ``radius``
    default to zeros.

    Attributes:
        types: channel name -> RenderMan type name (``"float"``, ``"color"``,
            ``"point"``, ``"vector"``, ``"normal"``, ``"matrix"``). A channel
            without an entry is ``float``, ``color`` or ``matrix`` by width.
        world_to_eye, world_to_ndc: (4, 4) float32 header matrices (row-major,
            as stored in .ptc files).
        format: (x resolution, y resolution, pixel aspect) of the header.
        file_version: the .ptc version it was read from (0 otherwise).
        compressed: whether the file it was read from was gzip-compressed.
    """

    def __init__(self, arrays=(), types=None, world_to_eye=None, world_to_ndc=None,
                 format=None):
        super().__init__(arrays)
        self.types = dict(types or {})
        self.world_to_eye = _matrix(world_to_eye)
        self.world_to_ndc = _matrix(world_to_ndc)
        self.format = tuple(format) if format is not None else (0.0, 0.0, 1.0)
        self.file_version = 0
        self.compressed = False

    @property
    def channels(self):
        """The channel names (every key but P, N and radius), in order."""
        return [k for k in self if k not in _GEOMETRY]

    @property
    def size(self):
        """The number of points."""
        return len(self["P"]) if "P" in self else 0

    def __repr__(self):
        chans = ", ".join(f"{self.types.get(k, '?')} {k}" for k in self.channels)
        return f"sss.Cloud({self.size} points; {chans or 'no channels'})"


def _matrix(m):
    np = _numpy()
    if m is None:
        return np.eye(4, dtype=np.float32)
    return np.asarray(m, dtype=np.float32).reshape(4, 4)


def _cloud(arrays, types, header):
    cloud = Cloud(arrays, types, header["world_to_eye"], header["world_to_ndc"],
                  header["format"])
    cloud.file_version = header["file_version"]
    cloud.compressed = header["compressed"]
    return cloud


def _parts(cloud, types=None):
    """(arrays, types, header) of a Cloud or a plain dict for the binding."""
    all_types = dict(getattr(cloud, "types", {}) or {})
    all_types.update(types or {})
    np = _numpy()
    header = {}
    for key in ("world_to_eye", "world_to_ndc", "format"):
        value = getattr(cloud, key, None)
        if value is not None:
            header[key] = np.asarray(value, dtype=np.float32).reshape(-1)
    return dict(cloud), all_types, header


def _native(name):
    """A file name (or option word) as the bytes the OS uses: any name
    os.fsdecode() gave back (undecodable bytes as surrogates) reaches the
    library unchanged, where a str with surrogates could not."""
    return _os.fsencode(name)


def _path_list(source):
    if isinstance(source, (str, bytes, _os.PathLike)):
        return [_native(source)]
    return [_native(s) for s in source]


def _is_cloud(source):
    return isinstance(source, dict)


def read_cloud(path):
    """Reads a .ptc (versions 0-2, plain or gzip) or .ply file into a Cloud.

    The arrays own the memory the library read into (no copy). Raises
    IoError (missing or unreadable file) and FormatError (corrupt, truncated,
    NaN/Inf data), with the file name and, where it applies, the point index
    (the exceptions' ``path`` and ``point`` attributes); a missing file is
    a FileNotFoundError.
    """
    _numpy()
    return _cloud(*_sss.read_cloud(_native(path)))


def write_cloud(path, cloud, *, types=None, ptcversion=0, compress=False):
    """Writes a Cloud (or any dict of arrays, see Cloud) atomically.

    The format is chosen by extension: .ptc (``ptcversion`` 0, 1 or 2, gzip
    with ``compress``) or .ply; any other name is a ValueError. ``types``
    adds or overrides channel types. The arrays are converted to float32 and
    copied once. Raises ValueError for arrays of the wrong shape and for
    NaN/Inf values, IoError when the file cannot be written.
    """
    name = _os.fsdecode(path)
    extension = _os.path.splitext(name)[1]
    if extension.lower() not in _CLOUD_EXTENSIONS:
        raise ValueError(f"{name}: unknown extension {extension or '(none)'!r}: "
                         "write_cloud writes .ptc or .ply files")
    arrays, all_types, header = _parts(cloud, types)
    _sss.write_cloud(_native(path), arrays, all_types, header, int(ptcversion),
                     bool(compress))


# Options that are flags on ptfilter's command line (no value).
_FLAGS = {"exact"}


# Options that may be given more than once (ptfilter -blocker).
_REPEATED = {"blocker"}


def _values(key, value):
    if isinstance(value, (str, bytes, _os.PathLike)):
        return [_native(value)]
    if isinstance(value, bool) or _is_numpy_bool(value):
        return ["1" if value else "0"]
    if isinstance(value, _numbers.Integral):
        return [str(int(value))]
    if isinstance(value, _numbers.Real):
        # repr() of a float reads back as the same double: the library gets
        # exactly the value ptfilter gets from the same digits.
        return [repr(float(value))]
    values = list(value)
    if key == "channels" and all(isinstance(v, str) for v in values):
        return [_native(",".join(values))]
    return [w for v in values for w in _values(key, v)]


def _is_numpy_bool(value):
    np = _sys.modules.get("numpy")  # not loaded: value is no numpy bool
    return np is not None and isinstance(value, np.bool_)


def _words(options):
    """ptfilter/brickmake command-line words of keyword options (None: left out)."""
    words = []
    for key, value in options.items():
        if value is None:
            continue
        if key in _FLAGS:
            if value:
                words.append("-" + key)
            continue
        if key in _REPEATED and not isinstance(value, (str, bytes, _os.PathLike)):
            for v in value:  # blocker=["a.ptc", "b.ptc"]: -blocker a.ptc -blocker b.ptc
                words.extend(["-" + key] + _values(key, v))
            continue
        words.append("-" + key)
        words.extend(_values(key, value))
    return words


def _warn(report):
    for w in report.get("warnings", []):
        _warnings.warn(w, RuntimeWarning, stacklevel=3)


def ssdiffusion(source, *, progress=None, **options):
    """Subsurface diffusion (ptfilter -ssdiffusion) in this process.

    ``source``: a Cloud (or dict of arrays), a file name, or a list of file
    names (merged as ptfilter merges its inputs). Keyword options are
    ptfilter's, by the same names: ``material``, ``unitlength``,
    ``scattering``, ``absorption``, ``albedo`` (r, g, b or ``"fromfile"``),
    ``diffusemeanfreepath``, ``ior``, ``maxsolidangle``, ``profile``,
    ``criterion``, ``exact``, ``areachannel``, ``radiancechannel``,
    ``keepchannels``, ``isa`` and ``threads`` (0 = all cores). They are
    checked by the same code as ptfilter's options, so an impossible value
    raises UsageError or ValueError with ptfilter's message.

    ``progress``: a callable (done, total), called each time the integer
    percentage grows, with the GIL held; an exception it raises cancels the
    run and is raised here. Ctrl-C cancels too.

    Returns the output Cloud (P, N, radius, ``color _ssdiffusion``, plus the
    input's channels with keepchannels=True), bit for bit the cloud the
    ptfilter executable writes for the same options. The report (material
    values, timings) is its ``report`` attribute; the library's warnings are
    issued as RuntimeWarning.
    """
    _numpy()
    if _is_cloud(source):
        src = _parts(source)
    else:
        src = _path_list(source)
    arrays, types, header, report = _sss.ssdiffusion(src, _words(options), progress)
    _warn(report)
    cloud = _cloud(arrays, types, header)
    cloud.report = report
    return cloud


def ptfilter(inputs, output, *, progress=None, **options):
    """ptfilter -ssdiffusion [options] inputs... output, file to file.

    What the executable does, in this process and in as little memory (the
    inputs are streamed): the output file is byte for byte the executable's.
    Takes ssdiffusion()'s options plus ``compress``, ``ptcversion`` and
    ``frame`` (expands %04d, #### and $F4 in the file names). Returns the
    report dict.
    """
    report = _sss.ptfilter(_path_list(inputs), _native(output), _words(options),
                           progress)
    _warn(report)
    return report


def make_brickmap(source, output, *, progress=None, **options):
    """Builds a brick map (brickmake) from clouds and writes it atomically.

    ``source``: a file name, a list of file names, a Cloud or a list of
    Clouds (merged). Options are brickmake's: ``maxerror`` (default 0.002),
    ``maxdepth`` (15), ``radiusscale`` (1), ``ignorenormals``,
    ``omitgeometry``, ``channels`` (a list or "a,b"; default every float and
    color channel), ``threads`` and ``frame``. The map is the one brickmake
    builds for the same options (only its provenance text differs). Returns
    a report dict (points, bricks, file_size, seconds).
    """
    if _is_cloud(source):
        src = [_parts(source)]
    elif not isinstance(source, (str, bytes, _os.PathLike)) and source and all(
            _is_cloud(s) for s in source):
        src = [_parts(s) for s in source]
    else:
        src = _path_list(source)
    return _sss.make_brickmap(src, _native(output), _words(options), progress)


def isa_names():
    """The kernels' instruction-set paths this CPU runs (values of ``isa=``)."""
    return _sss.isa_names()


def _lookup(native, points, channel, normals, filterradius, threads, return_found):
    """texture3d at one point (3 numbers) or many ((N, 3)); see BrickMap.lookup."""
    np = _numpy()
    pts = np.asarray(points, dtype=np.float32)
    single = pts.ndim == 1
    if single:
        if pts.shape != (3,):
            raise ValueError("lookup: a point is 3 numbers, points an (N, 3) array "
                             f"(got shape {pts.shape})")
        pts = pts.reshape(1, 3)
    if normals is not None:
        normals = np.asarray(normals, dtype=np.float32)
        if normals.shape == (3,):  # one normal for every point
            normals = np.broadcast_to(normals, pts.shape)
    if single:
        radius = np.asarray(filterradius, dtype=np.float32)
        if radius.shape == (1,):
            filterradius = radius.reshape(())
    values, found = native.lookup(pts, channel, normals, filterradius, int(threads))
    if single:
        values, found = values[0], bool(found[0])
    return (values, found) if return_found else values


class BrickMap:
    """A brick map file opened for texture3d lookups (sss::BrickMap).

    Bricks are read on demand into a cache of at most ``cache_bytes``.
    Raises IoError (FileNotFoundError when missing) and FormatError
    (corrupt, truncated, wrong version).
    """

    def __init__(self, path, cache_bytes=256 << 20):
        self._map = _sss.BrickMap(_native(path), int(cache_bytes))
        self.path = _os.fsdecode(path)

    @property
    def info(self):
        """The header as a dict (channels, bounding box, settings, totals)."""
        return self._map.info

    @property
    def channels(self):
        """[(name, type)] of the map's channels."""
        return self._map.info["channels"]

    def lookup(self, points, channel=None, *, normals=None, filterradius=0.0, threads=0,
               return_found=False):
        """texture3d at many points at once, or at one.

        ``points``: (N, 3) array, or one point (3 numbers); ``normals``: the
        surface normals, (N, 3) or one for every point (None: the map's
        no-normal tree, which holds only points baked without normals);
        ``filterradius``: a number or an (N,) array (0: the finest data).
        ``channel``: a channel name, a list of names, or None for every
        channel (in order). Runs without the GIL on ``threads`` threads (0 =
        all cores); the values do not depend on the thread count.

        Returns an (N, k) float32 array (k = the channels' widths summed), or
        (k,) for one point; where the map has no data the values are 0. With
        ``return_found`` also an (N,) bool array of the points that had data
        (a bool for one point).
        """
        return _lookup(self._map, points, channel, normals, filterradius, threads,
                       return_found)

    def verify(self):
        """Reads and checks every brick (what brickinfo does); returns the count."""
        return self._map.verify()

    @property
    def bricks_loaded(self):
        """Bricks read from the file so far (cache misses)."""
        return self._map.bricks_loaded

    def __repr__(self):
        names = ", ".join(f"{t} {n}" for n, t in self.channels)
        return f"sss.BrickMap({self.path!r}; {names})"


class PointCloudLookup:
    """A point cloud opened for texture3d lookups as ``render`` does them
    when a shader names a .ptc or .ply file (sss::CloudTexture3d).

    ``source``: a file name, or a Cloud (or dict of arrays; copied). A
    lookup averages the nearest points whose normals agree with the
    query's (the 8 nearest, tent-weighted); it is found only near the
    points: within four median point radii (about two point spacings) or
    the filter radius. Raises IoError (FileNotFoundError when missing) and
    FormatError as read_cloud().
    """

    def __init__(self, source):
        if _is_cloud(source):
            self._cloud = _sss.CloudTexture3d(_parts(source))
            self.path = None
        else:
            self._cloud = _sss.CloudTexture3d(_native(source))
            self.path = _os.fsdecode(source)

    @property
    def channels(self):
        """[(name, type)] of the cloud's channels, in order."""
        return self._cloud.channels

    @property
    def size(self):
        """The number of points."""
        return self._cloud.size

    def lookup(self, points, channel=None, *, normals=None, filterradius=0.0, threads=0,
               return_found=False):
        """texture3d at many points at once, or at one: BrickMap.lookup's
        arguments and results, the renderer's values.

        ``filterradius`` widens only where a lookup counts as found (the
        renderer always averages the nearest points in a cloud). Non-finite
        points are misses, non-finite normals no normal. Runs without the
        GIL on ``threads`` threads (0 = all cores); each value depends only
        on its query.
        """
        return _lookup(self._cloud, points, channel, normals, filterradius, threads,
                       return_found)

    def __repr__(self):
        names = ", ".join(f"{t} {n}" for n, t in self.channels)
        where = repr(self.path) if self.path is not None else "a Cloud"
        return f"sss.PointCloudLookup({where}; {self.size} points; {names})"


def has_frame_pattern(path):
    """Whether ``path`` holds a frame pattern: %04d, %d, ####, $F4 or ${F}."""
    return _sss.has_frame_pattern(_os.fsdecode(path))


def expand_frame_pattern(path, frame=None, what="path"):
    """``path`` with its frame pattern replaced by ``frame``, as the tools'
    ``-frame`` does (docs/cli-conventions.md); ``path`` itself when it has
    none. UsageError, naming ``what``, for a pattern without a frame and for
    a lone ``#``."""
    return _sss.expand_frame_pattern(_os.fsdecode(path), frame, what)
