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

rangenet_like.onnx is a second, untrained network in the shape of the
models users bring (RangeNet++ / SalsaNext style): 3x3 convolutions with
batch normalisation and leaky ReLU, a convolution strided along the width
only (RangeNet++ keeps the 64 rows), nearest-neighbour Resize back up, a
skip connection (Add), a 1x1 classifier to SemanticKITTI's 20 learning
classes and a Softmax over them. Its weights are random (seed 38): its
labels mean nothing; it checks that OpenCV's importer runs these operators
and that a 20-class softmax output maps through rangenet_like.yaml, whose
classes list is the one a real RangeNet++ card needs.
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


# SemanticKITTI's learning classes in RangeNet++'s output order.
LEARNING_CLASSES = ["unlabeled", "car", "bicycle", "motorcycle", "truck", "other-vehicle", "person", "bicyclist",
                    "motorcyclist", "road", "parking", "sidewalk", "other-ground", "building", "fence", "vegetation",
                    "trunk", "terrain", "pole", "traffic-sign"]

RANGENET_CARD = """\
# Model card of tests/data/onnx/rangenet_like.onnx (written by
# scripts/make_onnx_fixture.py): an untrained RangeNet++-shaped network with
# random weights. With a real RangeNet++ / SalsaNext export, only 'model'
# changes: the rest is RangeNet++'s KITTI card.
model: rangenet_like.onnx
image: {height_px: 64, width_px: 2048, fov_up_deg: 3.0, fov_down_deg: -25.0}
channels:
  - {name: range, mean: 12.12, std: 12.32}
  - {name: x, mean: 10.88, std: 11.47}
  - {name: y, mean: 0.23, std: 6.91}
  - {name: z, mean: -1.04, std: 0.86}
  - {name: intensity, mean: 0.21, std: 0.16}
classes: [%s]
knn: {enabled: true, search_px: 5, k: 5, sigma_px: 1.0, cutoff_m: 1.0}
""" % ", ".join(LEARNING_CLASSES)


def make_rangenet_like():
    import numpy as np
    rng = np.random.default_rng(38)
    inits, nodes = [], []

    def tensor(name, array):
        inits.append(helper.make_tensor(name, TensorProto.FLOAT, list(array.shape),
                                        array.astype(np.float32).ravel().tolist()))
        return name

    def conv_bn_relu(x, name, cin, cout, stride=(1, 1)):
        w = tensor(name + "_w", rng.normal(0.0, 0.4, (cout, cin, 3, 3)))
        nodes.append(helper.make_node("Conv", [x, w], [name + "_c"], kernel_shape=[3, 3], pads=[1, 1, 1, 1],
                                      strides=list(stride)))
        bn = [tensor(name + "_" + k, v) for k, v in (("scale", rng.uniform(0.5, 1.5, cout)),
                                                      ("bias", rng.normal(0.0, 0.1, cout)),
                                                      ("mean", rng.normal(0.0, 0.1, cout)),
                                                      ("var", rng.uniform(0.5, 1.5, cout)))]
        nodes.append(helper.make_node("BatchNormalization", [name + "_c"] + bn, [name + "_bn"], epsilon=1e-5))
        nodes.append(helper.make_node("LeakyRelu", [name + "_bn"], [name], alpha=0.1))
        return name

    e1 = conv_bn_relu("range_image", "enc1", 5, 8)
    e2 = conv_bn_relu(e1, "enc2", 8, 16, stride=(1, 2))            # width / 2, as RangeNet++'s encoder
    d1 = conv_bn_relu(e2, "dec1", 16, 8)
    scales = tensor("up_scales", np.array([1.0, 1.0, 1.0, 2.0]))
    roi = tensor("up_roi", np.zeros(0))  # required (and unused) at opset 11
    nodes.append(helper.make_node("Resize", [d1, roi, scales], ["up"], mode="nearest"))
    nodes.append(helper.make_node("Add", ["up", e1], ["skip"]))
    wc = tensor("cls_w", rng.normal(0.0, 0.5, (20, 8, 1, 1)))
    bc = tensor("cls_b", rng.normal(0.0, 0.1, 20))
    nodes.append(helper.make_node("Conv", ["skip", wc, bc], ["logits"], kernel_shape=[1, 1]))
    nodes.append(helper.make_node("Softmax", ["logits"], ["probabilities"], axis=1))
    inp = helper.make_tensor_value_info("range_image", TensorProto.FLOAT, [1, 5, 64, 2048])
    out = helper.make_tensor_value_info("probabilities", TensorProto.FLOAT, [1, 20, 64, 2048])
    graph = helper.make_graph(nodes, "semlio_rangenet_like", [inp], [out], initializer=inits)
    model = helper.make_model(graph, producer_name="semlio scripts/make_onnx_fixture.py",
                              opset_imports=[helper.make_opsetid("", 11)])
    model.ir_version = 6
    onnx.checker.check_model(model)
    return model


def main():
    out_dir = sys.argv[1] if len(sys.argv) > 1 else os.path.join(os.path.dirname(__file__), "..", "tests", "data", "onnx")
    os.makedirs(out_dir, exist_ok=True)
    for stem, model, card_name, card in (("tiny_linear", make_model(), "tiny_kitti.yaml", KITTI_CARD),
                                         ("rangenet_like", make_rangenet_like(), "rangenet_like.yaml", RANGENET_CARD)):
        path = os.path.join(out_dir, stem + ".onnx")
        with open(path, "wb") as f:
            f.write(model.SerializeToString())
        with open(os.path.join(out_dir, card_name), "w") as f:
            f.write(card)
        print(f"wrote {path} ({os.path.getsize(path)} bytes) and {card_name}")

if __name__ == "__main__":
    main()
