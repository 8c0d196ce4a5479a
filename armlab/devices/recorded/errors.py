"""The recorded camera's one error type (InvalidInput, a ValueError: bad input, not a device fault)."""

from armlab.errors import InvalidInput


class RecordingError(InvalidInput):
    """A recording (folder, bag or intrinsics file) cannot be played; the message names the file and the fault."""
