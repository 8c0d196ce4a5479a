"""Make the arm meshes the 3-D panel loads (web/meshes/<arm>/) from the vendors' published ones, sized for a
fast first paint: binary STL, vertices merged on a grid (vertex clustering; triangles that collapse dropped),
normals left to the browser.

    python scripts/arm_meshes.py --interbotix DIR --ur DIR

DIR: a checkout of github.com/Interbotix/interbotix_ros_manipulators (BSD-3, Trossen Robotics) and of
github.com/UniversalRobots/Universal_Robots_ROS2_Description (BSD-3, Universal Robots A/S). Which file goes
to which link, and its origin there, is config/arm_meshes/<arm>.yaml (the vendors' URDF numbers).
"""

from __future__ import annotations

import argparse
import shutil
from pathlib import Path

import numpy as np

REPO = Path(__file__).resolve().parents[1]
OUT = REPO / "web" / "meshes"
INTERBOTIX_DIR = "interbotix_ros_xsarms/interbotix_xsarm_descriptions/meshes/rx200_meshes"
UR_DIR = "meshes/ur3/collision"  # the collision STLs: the arm's shape, a tenth of the visual Collada's size
# (source folder, output folder, grid cell in the file's units, licence file in the checkout)
SOURCES = {
    "rx200": ("interbotix", INTERBOTIX_DIR, 2.0, "LICENSE"),  # millimetres
    "ur3": ("ur", UR_DIR, 0.004, "LICENSE"),  # metres
}


def read_stl(path: Path) -> np.ndarray:
    """(n, 3, 3) triangle vertices of a binary STL."""
    data = path.read_bytes()
    count = int(np.frombuffer(data, dtype="<u4", count=1, offset=80)[0])
    record = np.dtype([("normal", "<f4", 3), ("vertices", "<f4", (3, 3)), ("attr", "<u2")])
    if 84 + count * record.itemsize != len(data):
        raise ValueError(f"{path}: not a binary STL ({len(data)} bytes for {count} triangles)")
    return np.frombuffer(data, dtype=record, count=count, offset=84)["vertices"].astype(np.float64)


def cluster(triangles: np.ndarray, cell: float) -> np.ndarray:
    """Vertex clustering: every vertex moves to the mean of the vertices in its grid cell; triangles with two
    corners in one cell, and duplicates, go."""
    vertices = triangles.reshape(-1, 3)
    keys = np.floor(vertices / cell).astype(np.int64)
    _, index, inverse = np.unique(keys, axis=0, return_index=True, return_inverse=True)
    inverse = inverse.reshape(-1)
    sums = np.zeros((len(index), 3))
    np.add.at(sums, inverse, vertices)
    means = sums / np.bincount(inverse)[:, None]
    faces = inverse.reshape(-1, 3)
    keep = (faces[:, 0] != faces[:, 1]) & (faces[:, 1] != faces[:, 2]) & (faces[:, 0] != faces[:, 2])
    faces = faces[keep]
    _, unique_rows = np.unique(np.sort(faces, axis=1), axis=0, return_index=True)
    faces = faces[np.sort(unique_rows)]
    return means[faces]


def write_stl(path: Path, triangles: np.ndarray, header: str) -> None:
    record = np.dtype([("normal", "<f4", 3), ("vertices", "<f4", (3, 3)), ("attr", "<u2")])
    out = np.zeros(len(triangles), dtype=record)
    normals = np.cross(triangles[:, 1] - triangles[:, 0], triangles[:, 2] - triangles[:, 0])
    lengths = np.linalg.norm(normals, axis=1, keepdims=True)
    out["normal"] = normals / np.where(lengths > 0, lengths, 1.0)
    out["vertices"] = triangles
    path.write_bytes(header.encode()[:80].ljust(80, b" ") + np.uint32(len(out)).tobytes() + out.tobytes())


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--interbotix", type=Path, required=True)
    parser.add_argument("--ur", type=Path, required=True)
    args = parser.parse_args()
    roots = {"interbotix": args.interbotix, "ur": args.ur}
    for arm, (vendor, folder, cell, licence) in SOURCES.items():
        out = OUT / arm
        out.mkdir(parents=True, exist_ok=True)
        total_in = total_out = 0
        for source in sorted((roots[vendor] / folder).glob("*.stl")):
            triangles = read_stl(source)
            reduced = cluster(triangles, cell)
            write_stl(out / source.name, reduced, f"{arm} {source.name}: vertex-clustered ({cell:g})")
            total_in += source.stat().st_size
            total_out += (out / source.name).stat().st_size
            print(f"{arm}/{source.name}: {len(triangles)} -> {len(reduced)} triangles")
        shutil.copyfile(roots[vendor] / licence, out / "LICENSE")
        print(f"{arm}: {total_in} -> {total_out} bytes")


if __name__ == "__main__":
    main()
