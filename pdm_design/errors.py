"""Errors the tool reports to people. None of them should ever surface as a traceback."""

from __future__ import annotations


class PdmError(Exception):
    """Base class for errors with a message meant for the user."""


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
