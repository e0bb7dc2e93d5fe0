# Copyright The sss Authors
# SPDX-License-Identifier: Apache-2.0
"""The sss module's exceptions (docs/python.md, Errors).

Each is an sss.Error and the builtin exception a Python caller would catch
anyway: a file the library cannot open is an OSError (a missing one a
FileNotFoundError) with errno, strerror and filename set; a bad value is a
ValueError. str(e) is the library's message, the text a tool prints after
"<tool> ERROR:". The binding (sss._sss) raises them.
"""

import builtins
import errno as _errno
import os


class _Brief(type):
    """dir() of a class lists only what the class itself defines, so that
    help() shows its own documentation without the dozens of members every
    exception (or dict) inherits. Instances are untouched: dir(e) lists
    everything."""

    def __dir__(cls):
        own = [n for n in vars(cls) if not n.startswith("_") or n == "__init__"]
        return sorted(own)


class Error(Exception, metaclass=_Brief):
    """Base class of every error the sss library reports."""

    __module__ = "sss"


class UsageError(Error, builtins.ValueError):
    """A bad option: an unknown keyword, a bad or missing value."""

    __module__ = "sss"


class ValueError(Error, builtins.ValueError):
    """An impossible value (a negative length, an albedo outside [0, 1], a
    missing channel, an array of the wrong shape, an unknown extension)."""

    __module__ = "sss"


class LimitError(Error, builtins.ValueError):
    """An input beyond one of the SSS_LIMIT_* limits (docs/limits.md)."""

    __module__ = "sss"


class OutOfMemoryError(Error, builtins.MemoryError):
    """A job that would not fit in memory."""

    __module__ = "sss"


class FormatError(Error, builtins.ValueError):
    """A file's content is malformed (bad magic, truncation, NaN/Inf data).

    ``path`` is the file, ``point`` the offending point's index (None when
    the error is not about one point).
    """

    __module__ = "sss"

    def __init__(self, message, path=None, point=None):
        super().__init__(message)
        self.path = path
        self.point = point

    def __reduce__(self):
        return (type(self), (str(self), self.path, self.point))


class IoError(Error, builtins.OSError):
    """A file could not be opened, read or written: an OSError whose
    ``errno`` and ``strerror`` are the operating system's (None and the
    library's reason when no system call failed) and whose ``filename`` (also
    ``path``) is the file. A missing file raises sss.FileNotFoundError, a
    subclass that is also the builtin FileNotFoundError."""

    __module__ = "sss"

    def __init__(self, message, path=None, errno=0):
        reason = message
        if path is not None and message.startswith(f"{path}: "):
            reason = message[len(path) + 2:]
        strerror = os.strerror(errno) if errno else reason
        builtins.OSError.__init__(self, errno or None, strerror, path)
        # args as every sss.Error's: the message alone.
        self.args = (message,)
        self._message = message

    @property
    def path(self):
        """The file (the same as ``filename``)."""
        return self.filename

    def __str__(self):
        return self._message

    def __reduce__(self):
        return (type(self), (self._message, self.filename, self.errno or 0))


class FileNotFoundError(IoError, builtins.FileNotFoundError):
    """A file to read that does not exist (errno ENOENT): both an sss.IoError
    and the builtin FileNotFoundError."""

    __module__ = "sss"


def io_error(message, path, errno):
    """The IoError for the library's error: FileNotFoundError for ENOENT."""
    cls = FileNotFoundError if errno == _errno.ENOENT else IoError
    return cls(message, path, errno)
