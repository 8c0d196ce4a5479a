"""The recorded camera's one error type (a ValueError: bad input, not a device fault)."""


class RecordingError(ValueError):
    """A recording (folder, bag or intrinsics file) cannot be played; the message names the file and the fault."""
