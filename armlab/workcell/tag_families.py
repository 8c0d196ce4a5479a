"""Tag families a detector decodes: the AprilTag library's families and OpenCV's ArUco dictionaries (DICT_...),
and how many codes each has."""

from __future__ import annotations

from armlab.errors import InvalidInput


def known_dictionary(name: str) -> str:
    """The name if OpenCV's ArUco module has it as a predefined dictionary (DICT_...), else InvalidInput."""
    import cv2

    if not name.startswith("DICT_") or not hasattr(cv2.aruco, name):
        raise InvalidInput(f"unknown OpenCV ArUco dictionary '{name}' (e.g. DICT_APRILTAG_36h11, DICT_4X4_250)")
    return name


def dictionary_size(name: str) -> int:
    """Number of markers in an OpenCV predefined dictionary or AprilTag family (ids are 0 .. size - 1)."""
    if name in APRILTAG_FAMILY_SIZES:
        return APRILTAG_FAMILY_SIZES[name]
    import cv2

    return int(cv2.aruco.getPredefinedDictionary(getattr(cv2.aruco, name)).bytesList.shape[0])


# AprilTag families the AprilTag 3 library decodes, and their number of codes (ids 0 .. n - 1).
APRILTAG_FAMILY_SIZES = {"tag36h11": 587, "tagStandard41h12": 2115, "tag25h9": 35, "tag16h5": 30,
                         "tagCircle21h7": 38, "tagCircle49h12": 65535, "tagStandard52h13": 48714, "tagCustom48h12": 42211}


def is_apriltag_family(name: str) -> bool:
    """True for an AprilTag library family name (tag36h11, tagStandard41h12, ...), False for DICT_ names."""
    return name in APRILTAG_FAMILY_SIZES


def known_family(name: str) -> str:
    """The name if the AprilTag library (family) or OpenCV's ArUco module (DICT_...) decodes it."""
    if is_apriltag_family(name):
        return name
    try:
        return known_dictionary(name)
    except ValueError:
        raise InvalidInput(f"unknown tag family '{name}': AprilTag families {sorted(APRILTAG_FAMILY_SIZES)} "
                         "or an OpenCV ArUco dictionary (DICT_APRILTAG_36h11, DICT_4X4_250, ...)") from None
