"""Errors the tool reports to people. None of them should ever surface as a traceback."""

from __future__ import annotations

import os
from typing import Any


class PdmError(Exception):
    """Base class for errors with a message meant for the user."""


def did_you_mean(word: Any, known) -> str:
    """"; did you mean 'x'?" for the closest of `known` to a mistyped word, else ""."""
    if not isinstance(word, str):
        return ""
    import difflib  # only on error paths

    close = difflib.get_close_matches(word, list(known), n=1, cutoff=0.6)
    return f"; did you mean '{close[0]}'?" if close else ""


class SpecError(PdmError):
    """A spec file that cannot be used: names the file, the key path, what was expected and what
    was found. The CLI prints it and exits with code 2."""

    def __init__(self, file: str, key: str, expected: str, found: str | None = None):
        self.file, self.key, self.expected, self.found = file, key, expected, found
        where = f"{file}: {key}" if key else file
        text = f"{where}: expected {expected}"
        if found is not None:
            text += f", found {found}"
        super().__init__(text)


class OutputError(PdmError):
    """An output file that could not be written (the path given cannot hold a file, or the disk
    refused it). `bad_input` says whether the path itself is at fault (exit 2) rather than the
    machine (a full disk: exit 1)."""

    _MACHINE = {28, 122, 5}  # ENOSPC, EDQUOT, EIO

    def __init__(self, path, error: OSError):
        self.path, self.bad_input = str(path), error.errno not in self._MACHINE
        reason = error.strerror or str(error)
        if isinstance(error, FileExistsError):  # mkdir of the folder met a file of that name
            reason = f"{error.filename} is a file, not a folder"
        elif error.filename and not _names_this_output(error, self.path):
            reason += f" ({error.filename})"
        super().__init__(f"cannot write {self.path}: {reason}")


def _names_this_output(error: OSError, path: str) -> bool:
    """Whether the OSError is about `path` itself or the temporary file written beside it
    (pdm_design.io names those `.NAME.*`): saying so again would only add noise."""
    named = [os.fspath(f) for f in (error.filename, error.filename2) if f is not None]
    here = os.path.split(path)
    return any(f == path or (os.path.dirname(f) == here[0]
                             and os.path.basename(f).startswith(f".{here[1]}."))
               for f in named)
