"""`aprt inputs` (runtime/cli/cmd_inputs.cc): the .npy it writes of a LiDAR
sequence holds exactly the raw-points inputs the training transform makes
(tools/aprt_tools/lidar_points.py), in order, every N-th scan; a missing
sequence is refused with exit code 2 and no file left behind.

  inputs_check.py APRT MODEL LIDAR_DIR OUT_DIR"""

import json
import os
import subprocess
import sys

import numpy as np

from aprt_tools.dataset import read_poses
from aprt_tools.lidar_bev import read_kitti
from aprt_tools.lidar_points import POINTS_KEYS, points_features
from aprt_tools.model_bin.reader import read


def main():
    aprt, model, data, out = sys.argv[1:5]
    os.makedirs(out, exist_ok=True)
    npy = os.path.join(out, "inputs.npy")
    r = subprocess.run([aprt, "inputs", "--model", model, "--data", data, "--out", npy,
                        "--every", "3"], capture_output=True, text=True)
    assert r.returncode == 0, r.stderr
    _, meta = read(open(model, "rb").read())
    samples = meta["input_shape"][1]
    geometry = dict(zip(POINTS_KEYS, meta["points"]))
    names = [n for n, _, _ in read_poses(data, "lidar_poses.txt")][::3]
    a = np.load(npy)
    assert a.shape == (len(names), samples, 1, 6), a.shape
    for k, name in enumerate(names):
        want, _ = points_features(read_kitti(os.path.join(data, name)), samples, geometry,
                                  meta["norm_mean"], meta["norm_std"])
        assert np.array_equal(a[k, :, 0, :3], want[:, :3]), f"scan {name}: coordinates differ"
        assert np.allclose(a[k, :, 0, 3:], want[:, 3:], rtol=0, atol=1e-6), f"scan {name}"
    bad = os.path.join(out, "missing.npy")
    r = subprocess.run([aprt, "inputs", "--model", model, "--data", data + "/nonexistent",
                        "--out", bad], capture_output=True, text=True)
    assert r.returncode == 2 and "lidar_poses.txt" in r.stderr + r.stdout, r.stderr
    assert not os.path.exists(bad)
    print(json.dumps(dict(scans=len(names), samples=samples)))


if __name__ == "__main__":
    main()
