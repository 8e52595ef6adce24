#!/usr/bin/python3
"""Writes the tiny ONNX model and model cards of tests/data/onnx/ (issue #38 part 3).

Usage: /usr/bin/python3 scripts/make_onnx_fixture.py [OUT_DIR]   (default tests/data/onnx)

Needs Debian's python3-onnx (installed here with apt-get when missing). Not a
trained network: tiny_linear.onnx is one 1x1 convolution whose six output
scores are exact functions of the five input slots s0..s4 (the range image
channels in the model card's order, already normalised):

    score0 = 0
    score1 = s0
    score2 = s1
    score3 = s2 - 1
    score4 = s3 + s4
    score5 = s4 - s3

so the output class of a pixel, argmax (first maximum on ties), is known for
every input. Each score has at most two non-zero terms (bias included), so
float32 gives the same value in any summation order: a test that computes the
argmax itself must agree with OpenCV's forward pass bit for bit. Every slot
moves a different score, so a wrong channel order, mean or std changes
classes. The input's height and width are symbolic: the model runs on any
image size.

The cards: tiny_kitti.yaml (RangeNet++'s KITTI card: 64 x 2048, +3/-25 deg,
channels range, x, y, z, intensity with RangeNet++'s means and stds) for the
command-line tools; the unit tests build their own cards in C++.
"""
import os
import subprocess
import sys

try:
    import onnx
    from onnx import TensorProto, helper
except ImportError:  # Debian's package, for /usr/bin/python3
    subprocess.run(["apt-get", "install", "-y", "-qq", "python3-onnx"], check=True)
    import onnx
    from onnx import TensorProto, helper

# Rows: output scores; columns: input slots s0..s4.
WEIGHTS = [
    [0, 0, 0, 0, 0],
    [1, 0, 0, 0, 0],
    [0, 1, 0, 0, 0],
    [0, 0, 1, 0, 0],
    [0, 0, 0, 1, 1],
    [0, 0, 0, -1, 1],
]
BIAS = [0, 0, 0, -1, 0, 0]

KITTI_CARD = """\
# Model card of tests/data/onnx/tiny_linear.onnx on RangeNet++'s KITTI range
# image (written by scripts/make_onnx_fixture.py). Not a trained network: its
# classes are a fixed function of the normalised channels (see the script),
# so labels are meaningless; it exercises semlio_run --labels onnx.
model: tiny_linear.onnx   # relative to this file
image:
  height_px: 64
  width_px: 2048
  fov_up_deg: 3.0
  fov_down_deg: -25.0
channels:                 # the network's input order; RangeNet++'s img_means / img_stds
  - {name: range, mean: 12.12, std: 12.32}
  - {name: x, mean: 10.88, std: 11.47}
  - {name: y, mean: 0.23, std: 6.91}
  - {name: z, mean: -1.04, std: 0.86}
  - {name: intensity, mean: 0.21, std: 0.16}
classes: [unlabeled, road, building, vegetation, car, pole]   # output index -> class
knn: {enabled: true, search_px: 5, k: 5, sigma_px: 1.0, cutoff_m: 1.0}
"""


def make_model():
    inp = helper.make_tensor_value_info("range_image", TensorProto.FLOAT, [1, 5, "height", "width"])
    out = helper.make_tensor_value_info("scores", TensorProto.FLOAT, [1, 6, "height", "width"])
    w = helper.make_tensor("W", TensorProto.FLOAT, [6, 5, 1, 1], [float(v) for row in WEIGHTS for v in row])
    b = helper.make_tensor("B", TensorProto.FLOAT, [6], [float(v) for v in BIAS])
    conv = helper.make_node("Conv", ["range_image", "W", "B"], ["scores"], kernel_shape=[1, 1])
    graph = helper.make_graph([conv], "semlio_tiny_linear", [inp], [out], initializer=[w, b])
    model = helper.make_model(graph, producer_name="semlio scripts/make_onnx_fixture.py",
                              opset_imports=[helper.make_opsetid("", 11)])
    model.ir_version = 6  # readable by OpenCV 4.6's importer and older onnx runtimes
    onnx.checker.check_model(model)
    return model


def main():
    out_dir = sys.argv[1] if len(sys.argv) > 1 else os.path.join(os.path.dirname(__file__), "..", "tests", "data", "onnx")
    os.makedirs(out_dir, exist_ok=True)
    model_path = os.path.join(out_dir, "tiny_linear.onnx")
    with open(model_path, "wb") as f:
        f.write(make_model().SerializeToString())
    with open(os.path.join(out_dir, "tiny_kitti.yaml"), "w") as f:
        f.write(KITTI_CARD)
    print(f"wrote {model_path} ({os.path.getsize(model_path)} bytes) and tiny_kitti.yaml")


if __name__ == "__main__":
    main()
