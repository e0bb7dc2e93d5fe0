"""sss: point clouds, subsurface diffusion and brick maps from Python.

The binding of the sss library (docs/python.md). Point clouds are dicts of
numpy arrays (:class:`Cloud`); the diffusion takes ptfilter's options as
keyword arguments and gives the same numbers as the ``ptfilter`` executable;
brick maps are built and looked up many points at a time. Long calls release
the GIL and report progress to a callback; errors are :class:`Error`
subclasses carrying the library's message.

Example::

    import sss
    cloud = sss.read_cloud("bake.ptc")
    out = sss.ssdiffusion(cloud, material="skin1", unitlength=0.1)
    sss.write_cloud("diffused.ptc", out)
    sss.make_brickmap(["diffused.ptc"], "diffused.bkm", maxerror=0.002)
    values = sss.BrickMap("diffused.bkm").lookup(out["P"], "_ssdiffusion",
                                                 normals=out["N"])
"""

import numbers
import os
import warnings

import numpy as np

from . import _sss
from ._sss import (
    Error,
    FormatError,
    IoError,
    LimitError,
    OutOfMemoryError,
    UsageError,
    __version__,
    expand_frame_pattern,
    has_frame_pattern,
)

# sss.ValueError derives from the builtin ValueError; it is left out of
# __all__ so that `from sss import *` does not hide the builtin.
ValueError = _sss.ValueError

__all__ = [
    "BrickMap",
    "Cloud",
    "Error",
    "FormatError",
    "IoError",
    "LimitError",
    "OutOfMemoryError",
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

_IDENTITY = np.eye(4, dtype=np.float32)
_GEOMETRY = ("P", "N", "radius")


class Cloud(dict):
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
    if m is None:
        return _IDENTITY.copy()
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
    return os.fsencode(name)


def _path_list(source):
    if isinstance(source, (str, bytes, os.PathLike)):
        return [_native(source)]
    return [_native(s) for s in source]


def _is_cloud(source):
    return isinstance(source, dict)


def read_cloud(path):
    """Reads a .ptc (versions 0-2, plain or gzip) or .ply file into a Cloud.

    The arrays own the memory the library read into (no copy). Raises
    IoError (missing or unreadable file) and FormatError (corrupt, truncated,
    NaN/Inf data), with the file name and, where it applies, the point index
    (the exceptions' ``path`` and ``point`` attributes).
    """
    return _cloud(*_sss.read_cloud(_native(path)))


def write_cloud(path, cloud, *, types=None, ptcversion=0, compress=False):
    """Writes a Cloud (or any dict of arrays, see Cloud) atomically.

    The format is chosen by extension: .ply, else .ptc (``ptcversion`` 0, 1
    or 2, gzip with ``compress``). ``types`` adds or overrides channel types.
    The arrays are converted to float32 and copied once. Raises ValueError
    for arrays of the wrong shape and for NaN/Inf values, IoError when the
    file cannot be written.
    """
    arrays, all_types, header = _parts(cloud, types)
    _sss.write_cloud(_native(path), arrays, all_types, header, int(ptcversion),
                     bool(compress))


# Options that are flags on ptfilter's command line (no value).
_FLAGS = {"exact"}


# Options that may be given more than once (ptfilter -blocker).
_REPEATED = {"blocker"}


def _values(key, value):
    if isinstance(value, (str, bytes, os.PathLike)):
        return [_native(value)]
    if isinstance(value, (bool, np.bool_)):
        return ["1" if value else "0"]
    if isinstance(value, numbers.Integral):
        return [str(int(value))]
    if isinstance(value, numbers.Real):
        # repr() of a float reads back as the same double: the library gets
        # exactly the value ptfilter gets from the same digits.
        return [repr(float(value))]
    values = list(value)
    if key == "channels" and all(isinstance(v, str) for v in values):
        return [_native(",".join(values))]
    return [w for v in values for w in _values(key, v)]


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
        if key in _REPEATED and not isinstance(value, (str, bytes, os.PathLike)):
            for v in value:  # blocker=["a.ptc", "b.ptc"]: -blocker a.ptc -blocker b.ptc
                words.extend(["-" + key] + _values(key, v))
            continue
        words.append("-" + key)
        words.extend(_values(key, value))
    return words


def _warn(report):
    for w in report.get("warnings", []):
        warnings.warn(w, RuntimeWarning, stacklevel=3)


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
    elif not isinstance(source, (str, bytes, os.PathLike)) and source and all(
            _is_cloud(s) for s in source):
        src = [_parts(s) for s in source]
    else:
        src = _path_list(source)
    return _sss.make_brickmap(src, _native(output), _words(options), progress)


def isa_names():
    """The kernels' instruction-set paths this CPU runs (values of ``isa=``)."""
    return _sss.isa_names()


class BrickMap:
    """A brick map file opened for texture3d lookups (sss::BrickMap).

    Bricks are read on demand into a cache of at most ``cache_bytes``.
    Raises IoError and FormatError (corrupt, truncated, wrong version).
    """

    def __init__(self, path, cache_bytes=256 << 20):
        self._map = _sss.BrickMap(_native(path), int(cache_bytes))
        self.path = os.fsdecode(path)

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
        """texture3d at many points at once.

        ``points``: (N, 3) array; ``normals``: (N, 3) array of the surface
        normals (None: the map's no-normal tree, which holds only points baked
        without normals); ``filterradius``: a number or an (N,) array (0: the
        finest data). ``channel``: a channel name, or None for every channel
        (in order). Runs without the GIL on ``threads`` threads (0 = all
        cores); the values do not depend on the thread count.

        Returns an (N, k) float32 array (k = the channel's width, or the sum
        of all widths); where the map has no data the values are 0. With
        ``return_found`` also an (N,) bool array of the points that had data.
        """
        values, found = self._map.lookup(points, channel, normals, filterradius,
                                         int(threads))
        return (values, found) if return_found else values

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
