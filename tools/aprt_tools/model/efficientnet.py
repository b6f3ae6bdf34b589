"""EfficientNet-B0..B3 in the module layout of the `efficientnet_pytorch` package.

Only the layout (module and parameter names, shapes, padding rule, BatchNorm
settings) follows that package, so that an upstream APR-Transformer checkpoint
loads with ``strict=True``. The forward pass computes the two endpoints the
pose network consumes and stops after the stage that produces the later one:
the blocks behind it, ``_conv_head``, ``_bn1`` and ``_fc`` exist only so the
checkpoint keys match.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import torch
from torch import nn
from torch.nn import functional as F

# (width, depth, resolution, dropout) per variant, from the EfficientNet paper.
VARIANTS = {
    "efficientnet-b0": (1.0, 1.0, 224, 0.2),
    "efficientnet-b1": (1.0, 1.1, 240, 0.2),
    "efficientnet-b2": (1.1, 1.2, 260, 0.3),
    "efficientnet-b3": (1.2, 1.4, 300, 0.3),
}


@dataclass(frozen=True)
class StageArgs:
    kernel: int
    stride: int
    expand: int
    in_ch: int
    out_ch: int
    repeats: int
    se_ratio: float = 0.25


# The seven MBConv stages of B0 before width/depth scaling.
B0_STAGES = (
    StageArgs(3, 1, 1, 32, 16, 1),
    StageArgs(3, 2, 6, 16, 24, 2),
    StageArgs(5, 2, 6, 24, 40, 2),
    StageArgs(3, 2, 6, 40, 80, 3),
    StageArgs(5, 1, 6, 80, 112, 3),
    StageArgs(5, 2, 6, 112, 192, 4),
    StageArgs(3, 1, 6, 192, 320, 1),
)

BN_MOMENTUM = 0.01  # efficientnet_pytorch: 1 - 0.99
BN_EPS = 1e-3


def round_filters(filters: int, width: float, divisor: int = 8) -> int:
    """Channel count after width scaling, rounded to a multiple of `divisor`."""
    if width == 1.0:
        return filters
    scaled = filters * width
    rounded = max(divisor, int(scaled + divisor / 2) // divisor * divisor)
    if rounded < 0.9 * scaled:  # never round down by more than 10 %
        rounded += divisor
    return int(rounded)


def round_repeats(repeats: int, depth: float) -> int:
    return int(math.ceil(depth * repeats))


def same_padding(size: int, kernel: int, stride: int) -> tuple[int, int]:
    """TensorFlow "same" padding for one axis: (before, after); after >= before."""
    out = math.ceil(size / stride)
    total = max((out - 1) * stride + kernel - size, 0)
    return total // 2, total - total // 2


class Conv2dStaticSamePadding(nn.Conv2d):
    """Conv2d with padding fixed at construction for one input size.

    The padding is TensorFlow's "same" rule for the given input size, which is
    asymmetric (more at the bottom/right) when the total is odd, e.g. for 3x3
    and 5x5 stride-2 convolutions on even sizes. It is applied by a
    ``ZeroPad2d`` child named ``static_padding`` (no parameters).
    """

    def __init__(self, in_ch: int, out_ch: int, kernel: int, stride: int = 1,
                 groups: int = 1, bias: bool = False, image_size: tuple[int, int] = (1, 1)):
        super().__init__(in_ch, out_ch, kernel, stride, padding=0, groups=groups, bias=bias)
        top, bottom = same_padding(image_size[0], kernel, stride)
        left, right = same_padding(image_size[1], kernel, stride)
        if top or bottom or left or right:
            self.static_padding = nn.ZeroPad2d((left, right, top, bottom))
        else:
            self.static_padding = nn.Identity()

    def forward(self, x: torch.Tensor) -> torch.Tensor:
        return F.conv2d(self.static_padding(x), self.weight, self.bias, self.stride,
                        0, self.dilation, self.groups)


def swish(x: torch.Tensor) -> torch.Tensor:
    # Written as x * sigmoid(x) (not F.silu) so the ONNX export matches the
    # upstream graph: Sigmoid followed by Mul.
    return x * torch.sigmoid(x)


class MBConvBlock(nn.Module):
    """Mobile inverted bottleneck with squeeze-and-excitation."""

    def __init__(self, kernel: int, stride: int, expand: int, in_ch: int, out_ch: int,
                 se_ratio: float, image_size: tuple[int, int]):
        super().__init__()
        self.stride = stride
        self.in_ch, self.out_ch = in_ch, out_ch
        mid = in_ch * expand
        if expand != 1:
            self._expand_conv = Conv2dStaticSamePadding(in_ch, mid, 1, image_size=image_size)
            self._bn0 = nn.BatchNorm2d(mid, momentum=BN_MOMENTUM, eps=BN_EPS)
        self.expand = expand
        self._depthwise_conv = Conv2dStaticSamePadding(mid, mid, kernel, stride, groups=mid,
                                                       image_size=image_size)
        self._bn1 = nn.BatchNorm2d(mid, momentum=BN_MOMENTUM, eps=BN_EPS)
        squeezed = max(1, int(in_ch * se_ratio))
        self._se_reduce = Conv2dStaticSamePadding(mid, squeezed, 1, bias=True)
        self._se_expand = Conv2dStaticSamePadding(squeezed, mid, 1, bias=True)
        self._project_conv = Conv2dStaticSamePadding(mid, out_ch, 1,
                                                     image_size=output_size(image_size, stride))
        self._bn2 = nn.BatchNorm2d(out_ch, momentum=BN_MOMENTUM, eps=BN_EPS)

    def forward(self, inputs: torch.Tensor) -> torch.Tensor:
        x = inputs
        if self.expand != 1:
            x = swish(self._bn0(self._expand_conv(x)))
        x = swish(self._bn1(self._depthwise_conv(x)))
        s = F.adaptive_avg_pool2d(x, 1)
        s = self._se_expand(swish(self._se_reduce(s)))
        x = torch.sigmoid(s) * x
        x = self._bn2(self._project_conv(x))
        if self.stride == 1 and self.in_ch == self.out_ch:
            x = x + inputs
        return x


def output_size(size: tuple[int, int], stride: int) -> tuple[int, int]:
    return (math.ceil(size[0] / stride), math.ceil(size[1] / stride))


class EfficientNet(nn.Module):
    """EfficientNet trunk; `endpoints()` returns the stride-8 and stride-16 maps."""

    def __init__(self, variant: str = "efficientnet-b0", image_size: int = 224):
        super().__init__()
        if variant not in VARIANTS:
            raise ValueError(f"unknown backbone {variant!r}; choose one of {sorted(VARIANTS)}")
        width, depth, _, _ = VARIANTS[variant]
        self.variant = variant
        size = (image_size, image_size)
        stem = round_filters(32, width)
        self._conv_stem = Conv2dStaticSamePadding(3, stem, 3, 2, image_size=size)
        self._bn0 = nn.BatchNorm2d(stem, momentum=BN_MOMENTUM, eps=BN_EPS)
        size = output_size(size, 2)
        blocks = []
        for stage in B0_STAGES:
            cin, cout = round_filters(stage.in_ch, width), round_filters(stage.out_ch, width)
            for i in range(round_repeats(stage.repeats, depth)):
                stride = stage.stride if i == 0 else 1
                blocks.append(MBConvBlock(stage.kernel, stride, stage.expand, cin, cout,
                                          stage.se_ratio, size))
                size = output_size(size, stride)
                cin = cout
        self._blocks = nn.ModuleList(blocks)
        head_in = round_filters(320, width)
        head = round_filters(1280, width)
        self._conv_head = Conv2dStaticSamePadding(head_in, head, 1, image_size=size)
        self._bn1 = nn.BatchNorm2d(head, momentum=BN_MOMENTUM, eps=BN_EPS)
        self._avg_pooling = nn.AdaptiveAvgPool2d(1)
        self._dropout = nn.Dropout(VARIANTS[variant][3])
        self._fc = nn.Linear(head, 1000)

    def endpoint_channels(self) -> tuple[int, int]:
        """Channels of (reduction_3, reduction_4): (40, 112) for B0."""
        strided = [i for i, b in enumerate(self._blocks) if b.stride > 1]
        return self._blocks[strided[2] - 1].out_ch, self._blocks[strided[3] - 1].out_ch

    def endpoints(self, x: torch.Tensor) -> tuple[torch.Tensor, torch.Tensor]:
        """(reduction_3, reduction_4): the last maps at stride 8 and stride 16.

        Same rule as efficientnet_pytorch's extract_endpoints: an endpoint is
        the input of a block that lowers the resolution. Blocks after the
        stride-16 endpoint are not run.
        """
        x = swish(self._bn0(self._conv_stem(x)))
        found = []
        for block in self._blocks:
            if block.stride > 1:
                found.append(x)
                if len(found) == 4:  # reduction_4 found: the rest never runs
                    break
            x = block(x)
        return found[2], found[3]
