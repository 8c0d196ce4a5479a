"""Load an armlab LeRobot export with LeRobot's own LeRobotDataset and compare it with what was recorded.

Runs in a Python that has LeRobot (and torch), not armlab's: bench/recording.py --lerobot writes the expected values
(from the MCAP, by armlab's reader) to an .npz and runs this with --lerobot-python. It imports nothing of armlab.

    /path/to/lerobot-venv/bin/python bench/lerobot_load_check.py DATASET_DIR EXPECTED.npz [--stride 1] [--backend pyav]

EXPECTED.npz: state (K, n) and action (K, n) float32, the recorded values at the K frame times; image_grid (K, 3, gh, gw)
float32, the colour frame shown at each frame time as block means in [0, 1] (blocks of `block` px). Checks: K items;
every item's observation.state and action equal (exactly) to the recorded; its timestamp k / fps; its camera frame a
(3, H, W) float32 image whose block means are within --image-tolerance of the recorded frame's; the episode and task.
Prints one line per check and exits 1 if any fails.
"""

from __future__ import annotations

import argparse
import sys
import time

import numpy as np


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("dataset")
    parser.add_argument("expected")
    parser.add_argument("--stride", type=int, default=1, help="check every n-th item's camera frame (states: all)")
    parser.add_argument("--backend", default=None, help="LeRobot's video backend (default: LeRobot's: torchcodec, else pyav)")
    parser.add_argument("--image-tolerance", type=float, default=0.04, help="largest block-mean difference (0..1)")
    args = parser.parse_args()

    import lerobot
    import torch
    from lerobot.datasets.lerobot_dataset import LeRobotDataset

    expected = np.load(args.expected)
    block = int(expected["block"])
    started = time.perf_counter()
    dataset = LeRobotDataset("armlab/export", root=args.dataset, video_backend=args.backend)
    loaded_s = time.perf_counter() - started
    print(f"lerobot {lerobot.__version__ if hasattr(lerobot, '__version__') else '?'} (torch {torch.__version__}), "
          f"video backend {dataset.video_backend}: LeRobotDataset loaded in {loaded_s:.2f} s: {dataset.num_episodes} episode(s), "
          f"{len(dataset)} frames at {dataset.fps} fps, features {sorted(dataset.features)}", flush=True)
    failures = []

    def check(ok: bool, text: str) -> None:
        print(("ok   " if ok else "FAIL ") + text, flush=True)
        if not ok:
            failures.append(text)

    frames = len(expected["state"])
    check(len(dataset) == frames, f"{len(dataset)} items, {frames} recorded frames")
    rows = dataset.hf_dataset[0:len(dataset)]  # every row, as LeRobot's transform gives them (tensors)
    states = torch.stack(list(rows["observation.state"])).numpy()
    actions = torch.stack(list(rows["action"])).numpy()
    state_diff = float(np.abs(states - expected["state"]).max())
    action_diff = float(np.abs(actions - expected["action"]).max())
    check(np.array_equal(states, expected["state"]), f"observation.state of all {frames} frames equals the recorded joints and "
          f"gripper at the frame times (largest difference {state_diff:g})")
    check(np.array_equal(actions, expected["action"]), f"action of all {frames} frames equals the recorded commands "
          f"(largest difference {action_diff:g})")

    camera = next(key for key in dataset.meta.video_keys)
    worst, checked, shape = 0.0, 0, None
    started = time.perf_counter()
    for index in range(0, frames, max(1, args.stride)):
        item = dataset[index]
        if abs(float(item["timestamp"]) - int(item["frame_index"]) / dataset.fps) > 1e-4:
            check(False, f"item {index}: timestamp {float(item['timestamp'])} is not frame_index / fps")
        if not np.array_equal(item["observation.state"].numpy(), expected["state"][index]):
            check(False, f"item {index}: observation.state differs")
        image = item[camera].numpy()  # (3, H, W) float32 in [0, 1]
        shape = image.shape
        c, h, w = image.shape
        grid = image[:, : h - h % block, : w - w % block].reshape(c, h // block, block, w // block, block).mean(axis=(2, 4))
        worst = max(worst, float(np.abs(grid - expected["image_grid"][index]).max()))
        checked += 1
    decode_s = time.perf_counter() - started
    check(worst <= args.image_tolerance, f"{checked} camera frames {shape} decoded through LeRobotDataset in {decode_s:.1f} s "
          f"({checked / decode_s:.0f} frames/s): each is the recorded colour frame of its time, largest {block}x{block}-px block "
          f"mean difference {worst:.4f} (<= {args.image_tolerance})")
    last = dataset[frames - 1]
    check(int(last["episode_index"]) == dataset.num_episodes - 1 and isinstance(last["task"], str),
          f"the last item: episode {int(last['episode_index'])}, task {last['task']!r}")
    chunk = [k / dataset.fps for k in range(10)]  # as a policy trains on it: an action chunk, the frame before and now
    windowed = LeRobotDataset("armlab/export", root=args.dataset, video_backend=args.backend,
                              delta_timestamps={"action": chunk, camera: [-1 / dataset.fps, 0.0]})
    item = windowed[frames // 2]
    check(tuple(item["action"].shape) == (10, expected["action"].shape[1]) and tuple(item[camera].shape[:1]) == (2,)
          and np.array_equal(item["action"].numpy(), expected["action"][frames // 2: frames // 2 + 10]),
          f"with delta_timestamps (an action chunk of 10, the camera at -1/fps and 0): item {frames // 2} has actions "
          f"{tuple(item['action'].shape)} equal to the recorded, camera {tuple(item[camera].shape)}")
    print("LeRobot load check: " + ("passed" if not failures else f"{len(failures)} FAILED"), flush=True)
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
