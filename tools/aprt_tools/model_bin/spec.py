"""Numbers of the model_bin format (model_bin/FORMAT.md is the normative text).

runtime/engine/model_format.h carries the same numbers for the C++ reader;
tests/tools/test_spec_agreement.py checks that the two agree.
"""

MAGIC = b"APRTMDL\x00"
VERSION_MAJOR = 1
# 1.1: int8 weights, 'quantization'; 1.2: the PointNet++ ops, 'points';
# 1.3: 'uncertainty'; 1.4: 'ensemble'
VERSION_MINOR = 5
HEADER_BYTES = 64
SECTION_ENTRY_BYTES = 32
TENSOR_ENTRY_BYTES = 64
OP_ENTRY_BYTES = 96
ALIGN = 64
ENDIAN_MARK = 0x01020304
MAX_SECTIONS = 16
MAX_OP_INPUTS = 8
MAX_OP_OUTPUTS = 2
MAX_OP_PARAMS = 12
MAX_RANK = 4


def fourcc(s: str) -> int:
    b = s.encode()
    return b[0] | b[1] << 8 | b[2] << 16 | b[3] << 24


SEC_META = fourcc("META")
SEC_STRS = fourcc("STRS")
SEC_TENS = fourcc("TENS")
SEC_OPSQ = fourcc("OPSQ")
SEC_WGHT = fourcc("WGHT")

DTYPE_F32, DTYPE_I8, DTYPE_I32, DTYPE_U8 = 1, 2, 3, 4
DTYPE_BYTES = {DTYPE_F32: 4, DTYPE_I8: 1, DTYPE_I32: 4, DTYPE_U8: 1}

KIND_CONST, KIND_ACTIVATION, KIND_INPUT, KIND_OUTPUT = 1, 2, 3, 4

OP_CONV2D = 1
OP_DWCONV2D = 2
OP_LINEAR = 3
OP_SQUEEZE_EXCITE = 4
OP_ADD = 5
OP_LAYERNORM = 6
OP_ATTENTION = 7
OP_ACTIVATION = 8
OP_CONCAT = 9
OP_CROSS_ATTENTION_1Q = 10
# 1.2: the raw-points modality (PointNet++; FORMAT.md "Point ops")
OP_FPS = 11
OP_BALL_GROUP = 12
OP_GROUP_MAX = 13
OP_THREE_INTERP = 14
OP_GRID_TOKENS = 15
OP_NAMES = {OP_CONV2D: "CONV2D", OP_DWCONV2D: "DWCONV2D", OP_LINEAR: "LINEAR",
            OP_SQUEEZE_EXCITE: "SQUEEZE_EXCITE", OP_ADD: "ADD", OP_LAYERNORM: "LAYERNORM",
            OP_ATTENTION: "ATTENTION", OP_ACTIVATION: "ACTIVATION", OP_CONCAT: "CONCAT",
            OP_CROSS_ATTENTION_1Q: "CROSS_ATTENTION_1Q", OP_FPS: "FPS",
            OP_BALL_GROUP: "BALL_GROUP", OP_GROUP_MAX: "GROUP_MAX",
            OP_THREE_INTERP: "THREE_INTERP", OP_GRID_TOKENS: "GRID_TOKENS"}

ACT_NONE, ACT_SILU, ACT_GELU, ACT_SIGMOID, ACT_RELU = 0, 1, 2, 3, 4

# META keys: (key, type, name). Types: U32 array, F32 array, STR (utf-8), BYTES.
T_U32, T_F32, T_STR, T_BYTES = 1, 2, 3, 4
META_KEYS = {
    1: (T_STR, "producer"),
    2: (T_BYTES, "source_sha256"),
    3: (T_STR, "source_name"),
    10: (T_U32, "modality"),
    11: (T_U32, "input_shape"),  # N, H, W, C of the input tensor
    12: (T_F32, "norm_mean"),
    13: (T_F32, "norm_std"),
    14: (T_U32, "resize_policy"),
    20: (T_F32, "pose_min"),
    21: (T_F32, "pose_max"),
    30: (T_STR, "backbone"),
    31: (T_U32, "d_model"),
    32: (T_U32, "nheads"),
    33: (T_U32, "enc_layers"),
    34: (T_U32, "dec_layers"),
    35: (T_U32, "dim_feedforward"),
    40: (T_F32, "val_error"),  # median position error (m), orientation error (deg)
    41: (T_STR, "config_json"),
    42: (T_STR, "quantization"),  # JSON: method, calibration set, per-op policy
    # 1.3: the calibration scales (position, rotation) of the confidence outputs 7..12
    43: (T_F32, "uncertainty"),
    # 1.4: the number of member networks averaged by the graph (aprt_tools ensemble)
    44: (T_U32, "ensemble"),
    # LiDAR BEV (modality 2): cell_m, x_min, y_min, height_threshold_m, clip_count
    50: (T_F32, "bev"),
    # LiDAR points (modality 3): crop_radius_m, coord_scale_m
    51: (T_F32, "points"),
}
META_BY_NAME = {name: (key, typ) for key, (typ, name) in META_KEYS.items()}
META_REQUIRED = ("producer", "source_sha256", "modality", "input_shape", "norm_mean", "norm_std",
                 "pose_min", "pose_max", "d_model", "nheads", "enc_layers", "dec_layers")

MODALITY_IMAGE, MODALITY_LIDAR_BEV, MODALITY_LIDAR_POINTS = 1, 2, 3
MODALITY_NAMES = {MODALITY_IMAGE: "image", MODALITY_LIDAR_BEV: "lidar_bev",
                  MODALITY_LIDAR_POINTS: "lidar_points"}
# How camera frames become the input square (see docs/preprocessing.md).
RESIZE_SHORTER_THEN_CENTER_CROP = 1
RESIZE_STRETCH = 2
