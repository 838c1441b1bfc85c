"""Checks that an output path of the command line can be written, made before any work runs.

A run that has computed for minutes should not end in a traceback because ``--out`` names a
file or ``--plot`` a format matplotlib cannot write. Missing parent directories are fine (they
are created when the output is written); what is refused is a path whose existing part is in
the way: a file where a directory must be, a directory where a file must be, a directory that
cannot be written.
"""

from __future__ import annotations

import os
from pathlib import Path

from sonar_gym.train import UsageError


def check_output_dir(option: str, path: Path) -> None:
    """Check that ``path`` is, or can be made, a writable directory.

    Raises:
        UsageError: ``path`` or one of its parents is an existing file, or the nearest
            existing directory cannot be written (the message names ``option`` and ``path``).
    """
    if path.is_dir():
        _check_writable(option, path, path)
        return
    if path.exists():
        raise UsageError(f"{option} {path}: is a file; give the path of a directory")
    _check_creatable(option, path, "a directory")


def check_output_file(option: str, path: Path) -> None:
    """Check that ``path`` can be written as a file (its parents made if missing).

    Raises:
        UsageError: ``path`` is an existing directory, a parent is an existing file, or the
            nearest existing directory cannot be written.
    """
    if path.is_dir():
        raise UsageError(f"{option} {path}: is a directory; give the path of a file")
    if path.exists():
        if not os.access(path, os.W_OK):
            raise UsageError(f"{option} {path}: the file exists and cannot be written")
        return
    _check_creatable(option, path, "a file")


def check_plot_file(option: str, path: Path) -> None:
    """:func:`check_output_file`, and the suffix must be a format matplotlib writes (no suffix:
    matplotlib's default format).

    Raises:
        UsageError: the file cannot be written, or its suffix is not a known image format (the
            message lists the formats).
    """
    check_output_file(option, path)
    suffix = path.suffix.lower().lstrip(".")
    if not suffix:
        return
    from matplotlib.backend_bases import FigureCanvasBase

    formats = sorted(FigureCanvasBase.get_supported_filetypes())
    if suffix not in formats:
        raise UsageError(
            f"{option} {path}: matplotlib cannot write {path.suffix!r} files; "
            f"use one of {['.' + name for name in formats]}"
        )


def _check_creatable(option: str, path: Path, what: str) -> None:
    """``path`` does not exist: its nearest existing ancestor must be a writable directory."""
    ancestor = path.parent
    while not ancestor.exists() and ancestor != ancestor.parent:
        ancestor = ancestor.parent
    if not ancestor.is_dir():
        raise UsageError(
            f"{option} {path}: cannot make {what} there, {ancestor} is a file, not a directory"
        )
    _check_writable(option, path, ancestor)


def _check_writable(option: str, path: Path, directory: Path) -> None:
    if not os.access(directory, os.W_OK | os.X_OK):
        shown = "" if directory == path else f" ({directory} is not writable)"
        raise UsageError(f"{option} {path}: cannot write there{shown}")
