# SPDX-License-Identifier: BSD-3-Clause
"""Writing the plots' files (part of ukdyn/plotting.py, which re-exports what is public here
and lends its figures and styles as `kit`, so that this file imports nothing of ukdyn: the
command runs it as a script beside plotting.py): the formats (:func:`parse_formats`), each file
written whole or not at all (:func:`write_replacing`, :func:`save`), and every figure of a run
in one process or, in the command, in forked copies of it taking the figures from a shared queue
(:func:`write_figures`)."""

import errno
import os
import stat
import sys
import tempfile

#: the file formats the figures can be written in (``--plot-format``)
FORMATS = ("png", "pdf", "svg")

#: the PNG encoder's zlib level: 1 encodes in three quarters of the time of the default 6, the
#: files an eighth larger (slider_crank's 7 figures: 0.134 s and 482 kB against 0.177 s and
#: 428 kB, the least of 8 encodings on a loaded machine)
PNG_COMPRESS_LEVEL = 1


def parse_formats(formats):
    """The formats of `formats` (a list, or comma-separated text) in order, each once.
    Raises ValueError naming the allowed formats for an unknown one or an empty list."""
    if isinstance(formats, str):
        formats = formats.split(",")
    out = []
    for f in formats:
        f = str(f).strip().lower()
        if f not in FORMATS:
            raise ValueError("unknown plot format '%s': the formats are %s"
                             % (f, ", ".join(FORMATS)))
        if f not in out:
            out.append(f)
    if not out:
        raise ValueError("no plot format given: the formats are %s" % ", ".join(FORMATS))
    return out


def _umask():
    """The process's umask (read from /proc where it can be, without changing it)."""
    try:
        with open("/proc/self/status", encoding="ascii") as f:
            for line in f:
                if line.startswith("Umask:"):
                    return int(line.split()[1], 8)
    except (OSError, ValueError):
        pass
    mask = os.umask(0o022)
    os.umask(mask)
    return mask


def write_replacing(path, write):
    """Writes `path` whole or not at all, safe in a directory that others can write: a path
    that exists and is not a regular file (a symbolic link, a FIFO, a directory) is refused with
    OSError before anything is written; write(f) fills a binary file object opened on a
    temporary of unpredictable name beside `path` (tempfile.mkstemp: O_EXCL, O_NOFOLLOW),
    which is then renamed over `path`, with the mode that open() would have given it. (The same
    function is in ukdyn/viewer.py, which is run on its own as a script.)"""
    path = os.fspath(path)
    try:
        mode = os.lstat(path).st_mode
    except FileNotFoundError:
        mode = None
    if mode is not None and not stat.S_ISREG(mode):
        raise OSError(errno.EEXIST, "exists and is not a regular file (a symbolic link, a FIFO "
                      "or a directory): not written over", path)
    directory, name = os.path.split(os.path.abspath(path))
    fd, temporary = tempfile.mkstemp(prefix="." + name + ".", suffix=".tmp", dir=directory)
    try:
        with os.fdopen(fd, "wb") as f:
            os.fchmod(f.fileno(), 0o666 & ~_umask())
            write(f)
        os.replace(temporary, path)
    except BaseException:
        try:
            os.remove(temporary)
        except OSError:
            pass
        raise


def save(fig, path, fmt=None, dpi=None):
    """Writes the figure to `path` whole or not at all (write_replacing). The format is `fmt`,
    or `path`'s extension; `dpi`: the resolution of a raster format (the figure's own when
    None)."""
    fmt = fmt or os.path.splitext(path)[1][1:]
    extra = {"pil_kwargs": {"compress_level": PNG_COMPRESS_LEVEL}} if fmt == "png" else {}
    write_replacing(path, lambda f: fig.savefig(f, dpi=dpi or "figure", format=fmt, **extra))


def write_figures(kit, table, meta, directory, formats=("png",), close=True, style_name="screen",
                  processes=1):
    """Writes every figure of :func:`figures` into `directory` as STEM.FORMAT for each format
    (``png``, ``pdf``, ``svg``) in the style `style_name` (:data:`STYLES`); returns the paths
    written. With `close`, the figures are closed afterwards. With `processes` > 1 (the
    command, whose process has no threads: os.fork is safe there), forked copies of this
    process, made after the imports, draw figures too, each taking the next one from a shared
    queue; a copy that fails raises RuntimeError here. `kit`: the plotting module (its
    FIGURES, styles and metadata)."""
    formats = parse_formats(formats)
    meta = kit.metadata(table, meta)
    figures = kit.FIGURES
    if processes <= 1 or not hasattr(os, "fork"):
        return _write(kit, table, meta, directory, formats, close, style_name, figures)
    # the queue: a pipe holding the figures' indices, one byte each (a read of one byte from a
    # pipe is atomic: each index goes to one process), dearest first (kit.COST: the longest
    # first, so that the processes finish together); end of file when all are taken
    taken, queue = os.pipe()
    os.write(queue, bytes(queue_order(figures, getattr(kit, "COST", {}))))
    os.close(queue)
    children = []
    try:
        for _ in range(processes - 1):
            pid = os.fork()
            if pid == 0:  # a copy: its figures, then out without running the parent's exits
                code = 1
                try:
                    _write(kit, table, meta, directory, formats, close, style_name,
                           _queued(taken, figures))
                    code = 0
                except BaseException:
                    import traceback
                    traceback.print_exc()
                finally:
                    sys.stderr.flush()
                    os._exit(code)
            children.append(pid)
        _write(kit, table, meta, directory, formats, close, style_name, _queued(taken, figures))
    finally:
        os.close(taken)
        failed = [pid for pid in children if os.waitpid(pid, 0)[1] != 0]
    if failed:
        raise RuntimeError("plotting: %d of the %d processes drawing the figures failed"
                           % (len(failed), processes))
    names = [os.path.join(directory, "%s.%s" % (stem, fmt)) for stem, _ in figures
             for fmt in formats]
    return [p for p in names if os.path.exists(p)]


def queue_order(figures, cost):
    """The indices of `figures` ((stem, function) pairs) dearest first by `cost` (stem → the
    typical seconds; 0 for one not in it), the order of FIGURES among equals: the order the
    processes of write_figures take them in."""
    return sorted(range(len(figures)), key=lambda i: -cost.get(figures[i][0], 0.0))


def _queued(fd, figures):
    """The entries of `figures` this process takes from the queue `fd`, one at a time."""
    while True:
        index = os.read(fd, 1)
        if not index:
            return
        yield figures[index[0]]


def _write(kit, table, meta, directory, formats, close, style_name, makers):
    """Draws and writes the figures of `makers` ((stem, function) pairs); the paths written."""
    written = []
    with kit.style(style_name):  # (savefig reads some rc settings too: the fonts' types)
        for stem, make in makers:
            fig = make(table, meta)
            if fig is None:
                continue
            try:
                kit._module("plotting_layout").settle(fig)  # laid out once for every format
                for fmt in formats:
                    path = os.path.join(directory, "%s.%s" % (stem, fmt))
                    save(fig, path, fmt, kit.DPI)
                    written.append(path)
            finally:
                if close:
                    kit._plt().close(fig)
    return written
