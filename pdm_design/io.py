"""File output that is written whole or not at all."""

from __future__ import annotations

import errno
import os
import stat
import tempfile
from contextlib import contextmanager
from pathlib import Path

from .errors import OutputError


def write_atomic(path: str | os.PathLike, data: str | bytes) -> None:
    """Write data to path via a temporary file in the same folder and an atomic rename.
    OutputError (naming the path) if the folder cannot be made or the disk refuses the data."""
    write_all({path: data})


def write_all(files: dict) -> None:
    """Write several files (path -> str or bytes) whole or not at all: every one goes to a
    temporary file first, and none is renamed into place unless all were written and no
    target is a folder. A device or a named pipe (/dev/null, a FIFO) is written to directly:
    renaming over it would replace it with a regular file."""
    temps: dict[Path, str] = {}
    try:
        for path, data in files.items():
            path = Path(path)
            if _is_special(path):
                _guard(path, _write_into, path, data)
                continue
            temps[path] = _guard(path, _write_temp, path, data)
        for path in temps:
            if path.is_dir():
                raise OutputError(path, IsADirectoryError(errno.EISDIR, "Is a directory"))
        for path, tmp in temps.items():
            _guard(path, _publish, tmp, path)
    finally:
        for tmp in temps.values():
            Path(tmp).unlink(missing_ok=True)


def _guard(path: Path, action, *args):
    """action(*args), its OSError as an OutputError naming path."""
    try:
        return action(*args)
    except OSError as error:
        raise OutputError(path, error) from error


def _is_special(path: Path) -> bool:
    try:
        mode = path.stat().st_mode
    except OSError:
        return False
    return not (stat.S_ISREG(mode) or stat.S_ISDIR(mode))


def _write_into(path: Path, data: str | bytes) -> None:
    with path.open("wb" if isinstance(data, bytes) else "w") as handle:
        handle.write(data)


def _write_temp(path: Path, data: str | bytes) -> str:
    path.parent.mkdir(parents=True, exist_ok=True)
    mode = "wb" if isinstance(data, bytes) else "w"
    fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=f".{path.name}.", suffix=".tmp")
    try:
        with os.fdopen(fd, mode) as handle:
            handle.write(data)
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise
    return tmp


@contextmanager
def atomic_path(path: str | os.PathLike):
    """Yield a temporary path beside `path` for a writer that wants a file name (matplotlib's
    savefig); it becomes `path` only if the block finishes, else it is removed. OSErrors, the
    writer's included, become OutputError naming the path."""
    path = Path(path)
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=f".{path.stem}.", suffix=path.suffix)
        os.close(fd)
    except OSError as error:
        raise OutputError(path, error) from error
    try:
        yield Path(tmp)
        _publish(tmp, path)
    except OSError as error:
        raise OutputError(path, error) from error
    finally:
        Path(tmp).unlink(missing_ok=True)


def _publish(tmp: str, path: Path) -> None:
    """Give the temporary file ordinary permissions (mkstemp makes it private), then rename."""
    umask = os.umask(0)
    os.umask(umask)
    os.chmod(tmp, 0o666 & ~umask)
    os.replace(tmp, path)


def check_output(path: str | os.PathLike, option: str, *, folder: bool = False,
                 names: tuple[str, ...] = (), new_folders: bool = True) -> None:
    """Refuse an output path that cannot be written, before any work is done: SpecError
    ("command line", option, ...; exit 2). `folder`: the path is a folder the command writes
    `names` into (made if missing); else a file. new_folders=False: the folder a file goes in
    must exist already (no folders are made for it). Nothing is created here."""
    from .errors import SpecError

    path = Path(path)
    what = "a folder" if folder else "a file"
    if not str(path):
        raise SpecError("command line", option, f"the name of {what}", "''")
    if _is_special(path):  # /dev/null, a pipe: written into directly
        return
    if path.exists() and path.is_dir() != folder:
        raise SpecError("command line", option, f"{what} that can be written",
                        f"{path}, {'a file' if folder else 'a folder'}")
    parent = path if folder else path.parent
    for name in names if folder else ():
        if (parent / name).is_dir():
            raise SpecError("command line", option, f"{what} that can be written",
                            f"{path}, whose {name} is a folder")
    nearest = parent
    while not nearest.exists() and nearest != nearest.parent:
        nearest = nearest.parent
    if nearest != parent and not new_folders:
        raise SpecError("command line", option, f"{what} in an existing folder (no folders "
                        "are made for it)", f"{path}: no folder {parent}")
    if not nearest.is_dir():
        raise SpecError("command line", option, f"{what} that can be written",
                        f"{path}: {nearest} is a file, not a folder")
    if not os.access(nearest, os.W_OK | os.X_OK):
        raise SpecError("command line", option, f"{what} that can be written",
                        f"{path}: {nearest} is a folder this user cannot write in")
