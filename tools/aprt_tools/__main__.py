"""Command line: python3 -m aprt_tools <command> ... (see --help)."""

from __future__ import annotations

import argparse
import json
import os
import sys


def _blas_for_this_cpu():
    """Debian's OpenBLAS takes AMD Zen 4/5 for Haswell (AVX2) and leaves their
    AVX-512 unused; its SkylakeX kernels run the training's products ~1.4x
    faster there (measured: 54 vs 38 frames/s at 64x64). Only where the CPU has
    the AVX-512 subsets those kernels use, and before torch loads OpenBLAS."""
    if "OPENBLAS_CORETYPE" in os.environ:
        return
    try:
        with open("/proc/cpuinfo") as f:
            flags = next((line.split(":", 1)[1].split() for line in f
                          if line.startswith("flags")), [])
    except OSError:
        return
    if {"avx512f", "avx512bw", "avx512dq", "avx512vl", "avx512cd"} <= set(flags):
        os.environ["OPENBLAS_CORETYPE"] = "SkylakeX"


_blas_for_this_cpu()

from .model_bin import spec  # noqa: E402  (after the BLAS choice)


CONFIGS = ("tiny", "full", "tiny-bev", "bev", "tiny-points", "points")


def _floats(text: str) -> list:
    return [float(v) for v in text.split(",")]


def cmd_golden(a):
    from .golden import make_golden
    from .model.apr_transformer import AprConfig

    cfg = AprConfig.named(a.config, a.size)
    m = make_golden(cfg, a.out, seed=a.seed, opset=a.opset, count=a.count, portable=a.portable)
    shape = "x".join(str(v) for v in cfg.input_shape()[1:])
    print(f"golden: {a.config} input {shape} opset {a.opset} -> {a.out} "
          f"(relative output spread {m['min_relative_spread']:.2f})")
    if a.convert:
        a.onnx, a.output = f"{a.out}/model.onnx", f"{a.out}/model.aprt"
        a.config_json = f"{a.out}/model.json"
        cmd_convert(a)


def cmd_golden_int8(a):
    from .golden import make_golden_int8

    m = make_golden_int8(a.source, a.out, backbone=a.backbone, int8_attention=a.int8_attention,
                         bf16_attention=a.bf16_attention)
    print(f"golden-int8: {a.source} -> {a.out} ({m['ops']} int8 ops, {m['frames']} frames)")


def cmd_golden_ensemble(a):
    from .golden import make_golden_ensemble
    from .model.apr_transformer import AprConfig

    m = make_golden_ensemble(AprConfig.named(a.config), a.out, members=a.members, seed=a.seed)
    print(f"golden-ensemble: {a.config} -> {a.out} ({m['report']}; relative output spread "
          f"{m['min_relative_spread']:.2f})")


def cmd_export(a):
    import torch

    from .export import export_onnx
    from .model.apr_transformer import AprConfig, AprTransformer

    cfg = AprConfig.from_json(open(a.config_json).read()) if a.config_json else \
        AprConfig.named(a.config, a.size)
    model = AprTransformer(cfg)
    if a.weights:
        state = torch.load(a.weights, map_location="cpu")
        state = state.get("model_state_dict", state.get("state_dict", state))
        model.load_state_dict(state, strict=True)
    with open(a.output, "wb") as f:
        f.write(export_onnx(model, a.opset))
    with open(a.output.rsplit(".", 1)[0] + ".json", "w") as f:
        f.write(cfg.to_json())
    print(f"export: {a.output} (opset {a.opset}, input 1x{cfg.in_channels}x{cfg.image_size}x"
          f"{cfg.image_size})")


def cmd_convert(a):
    from .convert.convert import convert
    from .onnx.evaluate import UnsupportedOnnx

    config = json.load(open(a.config_json)) if getattr(a, "config_json", None) else None
    overrides = dict(pose_min=getattr(a, "pose_min", None), pose_max=getattr(a, "pose_max", None),
                     norm_mean=getattr(a, "mean", None), norm_std=getattr(a, "std", None))
    if config is None and getattr(a, "imagenet", False):
        overrides.setdefault("norm_mean", None)
        from .model.apr_transformer import IMAGENET_MEAN, IMAGENET_STD

        overrides["norm_mean"] = overrides["norm_mean"] or list(IMAGENET_MEAN)
        overrides["norm_std"] = overrides["norm_std"] or list(IMAGENET_STD)
    try:
        blob, report = convert(open(a.onnx, "rb").read(), source_name=a.onnx.rsplit("/", 1)[-1],
                               config=config, overrides=overrides)
    except UnsupportedOnnx as e:
        print(f"convert: {a.onnx}: {e}", file=sys.stderr)
        sys.exit(2)
    with open(a.output, "wb") as f:
        f.write(blob)
    print(f"convert: {a.output}: {report.text()}")


def cmd_quantize(a):
    from .convert.quantize import CalibrationError, quantize_model
    from .model_bin.reader import ModelBinError

    try:
        blob, report = quantize_model(open(a.model, "rb").read(), a.calibration, method=a.method,
                                      percentile=a.percentile, frames=a.frames,
                                      fp32_ops=a.fp32_ops, backbone=a.backbone,
                                      sensitivity=a.sensitivity,
                                      int8_attention=a.int8_attention,
                                      bf16_attention=a.bf16_attention)
    except (CalibrationError, ModelBinError, OSError) as e:
        print(f"quantize: {a.model}: {e}", file=sys.stderr)
        sys.exit(2)
    with open(a.output, "wb") as f:
        f.write(blob)
    if report.sensitivity:
        print("quantize: each op alone in int8, worst deviation from fp32 on the calibration "
              "frames (most costly first):")
        for name, m, d in sorted(report.sensitivity, key=lambda r: -r[1]):
            print(f"  {m:8.4f} m  {d:8.4f} deg  {name}")
    if a.verbose:
        for name, rows, k, n, scale, zero in report.ops:
            print(f"  {name}: {rows}x{k} -> {n}, input scale {scale:.4g} zero {zero}")
    print(f"quantize: {a.output}: {report.text()}")


def cmd_train(a):
    from .export import export_onnx
    from .train import train
    from .train_resume import resume

    if a.resume:
        given = [f"--{k.replace('_', '-')}" for k in ("data", "out", "init", "config_json")
                 if getattr(a, k)]
        if given:
            print(f"train: --resume continues the run as it was: {', '.join(given)} not taken "
                  "(its drives, folder and weights are the run's own)", file=sys.stderr)
            sys.exit(2)
    elif not a.data or not a.out:
        print("train: --data and --out are required (or --resume OUT)", file=sys.stderr)
        sys.exit(2)
    if a.minutes is None and not a.resume:
        a.minutes = 90.0

    from .model.apr_transformer import AprConfig

    resize = a.size if a.init else None  # a new input side for the initial model
    if a.size is None:
        a.size = 4096 if a.modality == "points" else 128
    preset = None
    if a.config_json and a.init:
        print("train: --config-json and --init both give the configuration: choose one",
              file=sys.stderr)
        sys.exit(2)
    if a.config_json:
        try:
            preset = AprConfig.from_json(open(a.config_json).read())
            if preset.points:
                from .model.pointnet2 import check_points_config

                check_points_config(preset.points)
        except (OSError, ValueError, TypeError) as e:
            print(f"train: {a.config_json}: {e}", file=sys.stderr)
            sys.exit(2)
    try:
        if a.resume:  # the run's own drives, folder and validation drive from here on
            model, cfg, run = resume(a.resume, a.minutes)
            a.data, a.out, a.val = run["data"], run["out"], run["val"]
        else:
            model, cfg = train(a.data, a.out, size=a.size, minutes=a.minutes, batch=a.batch,
                               lr=a.lr, seed=a.seed, threads=a.threads, hidden=a.hidden,
                               layers=a.layers, modality=a.modality, config=preset,
                               inputs=a.inputs, inputs_every=a.inputs_every, val=a.val,
                               augment_from=a.augment_from, init=a.init, workers=a.workers,
                               uncertainty=a.uncertainty, ema=a.ema, resize=resize,
                               bev_span_m=a.bev_span, chroma=a.chroma)
    except (OSError, ValueError) as e:
        print(f"train: {e}", file=sys.stderr)
        sys.exit(2)
    model.eval()
    with open(f"{a.out}/model.onnx", "wb") as f:
        f.write(export_onnx(model, 13))
    a.onnx, a.output, a.config_json = f"{a.out}/model.onnx", f"{a.out}/model.aprt", f"{a.out}/model.json"
    cmd_convert(a)
    if cfg.uncertainty:  # the confidence outputs' calibration, on the validation drive
        if not a.val:
            print("train: --uncertainty needs --val (the confidence is calibrated on it); "
                  f"{a.out}/model.aprt is not loadable until `aprt_tools confidence` runs",
                  file=sys.stderr)
            sys.exit(2)
        a.model, a.output = f"{a.out}/model.aprt", f"{a.out}/model.aprt"
        cmd_confidence(a)
    if a.int8:  # calibrated on the (first) training sequence itself (frames spread over it)
        a.model, a.calibration, a.output = f"{a.out}/model.aprt", a.data[0], f"{a.out}/model_int8.aprt"
        a.method, a.percentile, a.frames, a.fp32_ops = "percentile", 99.99, 64, None
        a.backbone = a.sensitivity = a.verbose = a.int8_attention = a.bf16_attention = False
        cmd_quantize(a)


def cmd_ensemble(a):
    from .ensemble import calibrated, extract
    from .model_bin.reader import ModelBinError

    try:
        if a.extract is not None:
            if len(a.models) != 1:
                raise ValueError("--extract takes one ensemble file")
            blob = extract(open(a.models[0], "rb").read(), a.extract)
            report = (f"member {a.extract} of {a.models[0]} (uncalibrated: `confidence "
                      f"{a.output} --val DRIVE` before running it; `train --init` as it is)")
        else:
            if not a.val:
                raise ValueError("--val DRIVE is required: the runtime refuses confidence "
                                 "outputs without their calibration")
            blob, report = calibrated([open(m, "rb").read() for m in a.models], a.models, a.val)
    except (ModelBinError, OSError, ValueError) as e:
        print(f"ensemble: {e}", file=sys.stderr)
        sys.exit(2)
    with open(a.output, "wb") as f:
        f.write(blob)
    print(f"ensemble: {a.output}: {report}")


def cmd_confidence(a):
    from .confidence import calibrate_file
    from .model_bin.reader import ModelBinError

    try:
        blob, report = calibrate_file(open(a.model, "rb").read(), a.val)
    except (ModelBinError, OSError, ValueError) as e:
        print(f"confidence: {a.model}: {e}", file=sys.stderr)
        sys.exit(2)
    with open(a.output or a.model, "wb") as f:
        f.write(blob)
    print(f"confidence: {a.output or a.model}: {report}")


def cmd_config(a):
    from .model.apr_transformer import AprConfig

    try:
        print(AprConfig.named(a.name, a.size, a.bev_span).to_json())
    except ValueError as e:
        print(f"config: {e}", file=sys.stderr)
        sys.exit(2)


def cmd_drive_times(a):
    from .drive_times import write_drive_times

    try:
        path, t = write_drive_times(a.folder, a.out, max_speed=a.max_speed,
                                    lateral_accel=a.lateral_accel, accel=a.accel)
    except (OSError, ValueError) as e:
        print(f"drive-times: {a.folder}: {e}", file=sys.stderr)
        sys.exit(2)
    print(f"drive-times: {path}: {len(t)} frames over {t[-1]:.1f} s "
          f"(mean {len(t) / max(t[-1], 1e-9):.1f} frames/s)")


def cmd_choose(a):
    from .choose import run

    drives = [os.path.join(a.data_root, d) if a.data_root else d for d in a.drives]
    try:
        out = run(a.aprt, a.model, a.config, drives, a.grid or [], a.baseline_model,
                  a.baseline_set, a.tolerance, a.jobs)
    except (ValueError, RuntimeError, OSError) as e:
        print(e, file=sys.stderr)
        sys.exit(2)
    if a.json:
        with open(a.json, "w") as f:
            json.dump(out, f, indent=1)
    sys.exit(0 if out["chosen"] is not None else 1)


def cmd_odometry(a):
    from .odometry import write_odometry

    camera = None
    if a.camera_xy:
        try:
            camera = tuple(float(v) for v in a.camera_xy.split(","))
            assert len(camera) == 2
        except (ValueError, AssertionError):
            print(f"odometry: --camera-xy wants X,Y in metres, not {a.camera_xy!r}",
                  file=sys.stderr)
            sys.exit(2)
    try:
        path, s = write_odometry(a.folder, a.out, speed_scale=a.speed_scale,
                                 speed_noise=a.speed_noise, yaw_rate_bias_dps=a.yaw_rate_bias,
                                 yaw_rate_noise_dps=a.yaw_rate_noise, seed=a.seed, camera=camera)
    except (OSError, ValueError) as e:
        print(f"odometry: {a.folder}: {e}", file=sys.stderr)
        sys.exit(2)
    print(f"odometry: {path}: {len(s)} samples over {s[-1, 0] - s[0, 0]:.1f} s, "
          f"{float(abs(s[:-1, 1] * (s[1:, 0] - s[:-1, 0])).sum()):.0f} m")


def cmd_plot_eval(a):
    from .plot_eval import EvalCsvError, plot_eval

    try:
        plot_eval(a.csv, a.out, labels=a.labels.split(",") if a.labels else None, title=a.title,
                  dataset=a.dataset, published=a.published)
    except (EvalCsvError, OSError) as e:
        print(f"plot-eval: {e}", file=sys.stderr)
        sys.exit(2)
    print(f"plot-eval: {a.out}")


def cmd_plot_timing(a):
    from .plot_timing import TimingReportError, plot_timing

    try:
        plot_timing(a.report, a.out)
    except (TimingReportError, OSError, KeyError) as e:
        print(f"plot-timing: {e}", file=sys.stderr)
        sys.exit(2)
    print(f"plot-timing: {a.out}")


def cmd_preprocess_golden(a):
    from .preprocess_golden import write_cases

    n = write_cases(a.out)
    print(f"preprocess-golden: {n} frames -> {a.out}")


def main(argv=None):
    p = argparse.ArgumentParser(prog="python3 -m aprt_tools", description=__doc__)
    sub = p.add_subparsers(dest="cmd", required=True)

    g = sub.add_parser("golden", help="write a varied-weight model, its ONNX, inputs and outputs")
    g.add_argument("--config", default="tiny", choices=CONFIGS)
    g.add_argument("--size", type=int, help="input side (default: the configuration's)")
    g.add_argument("--opset", type=int, default=13, choices=(13, 17))
    g.add_argument("--portable", action="store_true",
                   help="points models: also model_portable.onnx in standard ops (ONNX Runtime)")
    g.add_argument("--seed", type=int, default=1)
    g.add_argument("--count", type=int, default=3, help="number of inputs")
    g.add_argument("--convert", action="store_true", help="also write model.aprt")
    g.add_argument("--out", required=True)
    g.set_defaults(fn=cmd_golden)

    ge = sub.add_parser("golden-ensemble", help="an ensemble of varied-weight models with "
                        "confidence heads; inputs and the mean of their PyTorch outputs")
    ge.add_argument("--config", default="tiny", choices=("tiny", "tiny-bev"))
    ge.add_argument("--members", type=int, default=2)
    ge.add_argument("--seed", type=int, default=1)
    ge.add_argument("--out", required=True)
    ge.set_defaults(fn=cmd_golden_ensemble)

    gi = sub.add_parser("golden-int8", help="quantise a golden model; expected int8 outputs")
    gi.add_argument("source", help="folder written by golden --convert")
    gi.add_argument("--out", required=True)
    gi.add_argument("--backbone", action="store_true", help="also the backbone (depthwise too)")
    gia = gi.add_mutually_exclusive_group()
    gia.add_argument("--int8-attention", action="store_true", help="attention scores int8 too")
    gia.add_argument("--bf16-attention", action="store_true", help="attention in bf16")
    gi.set_defaults(fn=cmd_golden_int8)

    e = sub.add_parser("export", help="export the reference model (optionally a checkpoint)")
    e.add_argument("--config", default="full", choices=CONFIGS)
    e.add_argument("--config-json", help="configuration file written by export/train")
    e.add_argument("--size", type=int)
    e.add_argument("--weights", help="PyTorch checkpoint (upstream or ours), loaded strictly")
    e.add_argument("--opset", type=int, default=13, choices=(13, 17))
    e.add_argument("-o", "--output", required=True)
    e.set_defaults(fn=cmd_export)

    c = sub.add_parser("convert", help="ONNX -> model_bin")
    c.add_argument("onnx")
    c.add_argument("-o", "--output", required=True)
    c.add_argument("--config-json", help="the .json written next to the ONNX by export/golden")
    c.add_argument("--pose-min", type=_floats, help="x,y,z lower position bound (metres)")
    c.add_argument("--pose-max", type=_floats, help="x,y,z upper position bound (metres)")
    c.add_argument("--mean", type=_floats, help="per-channel normalisation mean")
    c.add_argument("--std", type=_floats, help="per-channel normalisation std")
    c.add_argument("--imagenet", action="store_true", help="ImageNet mean/std (image models)")
    c.set_defaults(fn=cmd_convert)

    q = sub.add_parser("quantize", help="int8 model from an fp32 model_bin and calibration frames")
    q.add_argument("model", help="fp32 .aprt written by convert")
    q.add_argument("--calibration", required=True,
                   help="DeepLoc-layout folder (poses.txt + images) or .npy [N,H,W,C] of "
                        "preprocessed inputs")
    q.add_argument("-o", "--output", required=True)
    q.add_argument("--method", default="percentile", choices=("minmax", "percentile", "mse"))
    q.add_argument("--percentile", type=float, default=99.99)
    q.add_argument("--frames", type=int, default=64, help="calibration frames used (evenly spread)")
    q.add_argument("--fp32-ops", help="regular expression: ops whose name matches stay fp32")
    q.add_argument("--backbone", action="store_true",
                   help="also the backbone's 1x1 convolutions (faster, less accurate)")
    qa = q.add_mutually_exclusive_group()
    qa.add_argument("--int8-attention", action="store_true",
                    help="attention scores Q K^T in int8 too (per row and head; softmax and "
                         "P V stay fp32)")
    qa.add_argument("--bf16-attention", action="store_true",
                    help="attention in bf16: Q, K, V and the softmax weights rounded to bf16, "
                         "products on AVX-512 BF16 where the CPU has it (softmax fp32)")
    q.add_argument("--sensitivity", action="store_true",
                   help="also measure each op alone in int8 (which ops cost accuracy)")
    q.add_argument("-v", "--verbose", action="store_true", help="print each int8 op's range")
    q.set_defaults(fn=cmd_quantize)

    cf = sub.add_parser("confidence", help="calibrate a model's per-pose confidence on a "
                                           "validation drive (model_bin 1.3 'uncertainty')")
    cf.add_argument("model", help="a model file with confidence outputs (train --uncertainty)")
    cf.add_argument("--val", required=True, help="a labelled drive no training used")
    cf.add_argument("-o", "--output", help="where to write (default: the model file itself)")
    cf.set_defaults(fn=cmd_confidence)

    en = sub.add_parser("ensemble", help="several fp32 models of one configuration as one "
                        "model file whose members the runtime merges (their spread in the "
                        "confidence), calibrated on --val")
    en.add_argument("models", nargs="+", help="2 to 8 fp32 model files with confidence "
                    "outputs and one configuration (their position bounds may differ)")
    en.add_argument("-o", "--output", required=True)
    en.add_argument("--val", help="the labelled validation drive to calibrate the "
                    "confidence on (as `confidence` does for one model); required to build")
    en.add_argument("--extract", type=int, metavar="I", help="instead: write member I of the "
                    "one ensemble file given (to continue training from it)")
    en.set_defaults(fn=cmd_ensemble)

    t = sub.add_parser("train", help="train the reference model on a DeepLoc-layout sequence (CPU)")
    t.add_argument("--data", nargs="+",
                   help="folder(s) with poses.txt and the images; several drives train together")
    t.add_argument("--val", help="a separate drive for the validation error (default: a "
                                 "contiguous tenth of the first --data held out)")
    t.add_argument("--init", help="a checkpoint.pth of an earlier run, or a model file (.aprt, "
                                  "fp32) converted from one: continue from its weights (its "
                                  "configuration and position bounds; new schedule)")
    t.add_argument("--uncertainty", action="store_true",
                   help="add the per-pose confidence heads (log error scales, outputs 7..12)")
    t.add_argument("--ema", type=float, default=0.0,
                   help="average the weights with this decay per step (e.g. 0.999) and ship "
                        "the average (default 0: the weights as trained)")
    t.add_argument("--augment-from", type=float, default=0.3,
                   help="fraction of the budget before colour augmentation ramps in (image)")
    t.add_argument("--chroma", action="store_true",
                   help="the colour augmentation also turns hue (+-25 deg) and scales "
                        "saturation (0.2-1.4, a tenth of the frames grey)")
    t.add_argument("--out")
    t.add_argument("--resume", metavar="OUT",
                   help="continue the run in folder OUT where it stopped (`touch OUT/STOP` "
                        "stops a run; a killed one goes on from its last checkpoint, saved "
                        "every 10 minutes): its drives, arguments, optimiser and schedule; "
                        "--minutes sets a new total budget")
    t.add_argument("--size", type=int, default=None,
                   help="image side / BEV grid (default 128), or points sampled (default 4096); "
                        "with --init: an image model trained at a new input side")
    t.add_argument("--minutes", type=float, default=None,
                   help="wall-clock training budget (default 90; with --resume: the run's own)")
    t.add_argument("--batch", type=int, default=16)
    t.add_argument("--lr", type=float, default=1e-4)
    t.add_argument("--seed", type=int, default=1)
    t.add_argument("--threads", type=int, default=2, help="CPU threads in all (shared by workers)")
    t.add_argument("--workers", type=int, default=1,
                   help="data-parallel processes (2 with --threads 2 is ~1.4x faster on two "
                        "cores than one process of two threads); --batch must divide by it")
    t.add_argument("--hidden", type=int, default=128, help="transformer width (d_model)")
    t.add_argument("--layers", type=int, default=3, help="encoder and decoder layers per branch")
    t.add_argument("--int8", action="store_true",
                   help="also write model_int8.aprt, calibrated on 64 frames of --data")
    t.add_argument("--inputs", help="points models: the .npy `aprt inputs` wrote of --data "
                                     "(the runtime's preprocessing, much faster than Python's)")
    t.add_argument("--inputs-every", type=int, default=1,
                   help="the --every given to `aprt inputs` (frames of --data used)")
    t.add_argument("--config-json", help="a whole configuration (from `aprt_tools config NAME`, "
                                          "edited) instead of the --modality preset")
    t.add_argument("--bev-span", type=float, default=32.0,
                   help="bev: the square the grid covers, metres, centred on the sensor (default "
                        "32, TransFuser's; cells of span/size)")
    t.add_argument("--modality", default="image", choices=("image", "bev", "points"),
                   help="bev: LiDAR scans (lidar_poses.txt) as BEV histograms, grid --size; "
                        "points: the same scans through PointNet++, --size points")
    t.set_defaults(fn=cmd_train)

    cf = sub.add_parser("config", help="print a preset configuration as JSON (to edit for "
                                       "train --config-json or export --config-json)")
    cf.add_argument("name", choices=CONFIGS)
    cf.add_argument("--size", type=int, help="image side / BEV grid / points sampled")
    cf.add_argument("--bev-span", type=float, default=32.0,
                    help="BEV models: the square the grid covers, metres (default 32)")
    cf.set_defaults(fn=cmd_config)

    dt = sub.add_parser("drive-times", help="times.txt for a sequence without one: a speed profile "
                                            "a vehicle could drive along its poses")
    dt.add_argument("folder", help="a DeepLoc-layout sequence (poses.txt)")
    dt.add_argument("--max-speed", type=float, default=13.9, help="m/s on straights (default 13.9)")
    dt.add_argument("--lateral-accel", type=float, default=3.0,
                    help="m/s^2 in curves: the speed there is sqrt(a / curvature) (default 3)")
    dt.add_argument("--accel", type=float, default=2.0,
                    help="m/s^2 of acceleration and braking between them (default 2)")
    dt.add_argument("--out", help="where to write (default FOLDER/times.txt)")
    dt.set_defaults(fn=cmd_drive_times)

    od = sub.add_parser("odometry", help="odometry.txt for a sequence: the speed and yaw rate its "
                                         "vehicle's bus would carry, with their errors")
    od.add_argument("folder", help="a DeepLoc-layout sequence (poses.txt; times.txt if any)")
    od.add_argument("--speed-scale", type=float, default=0.01,
                    help="speed scale error, drawn once in +-this (default 0.01: 1 %%)")
    od.add_argument("--speed-noise", type=float, default=0.05,
                    help="white noise on each speed sample, m/s (default 0.05)")
    od.add_argument("--yaw-rate-bias", type=float, default=0.2,
                    help="gyro bias, drawn once in +-this, deg/s (default 0.2)")
    od.add_argument("--yaw-rate-noise", type=float, default=0.5,
                    help="white noise on each yaw rate sample, deg/s (default 0.5)")
    od.add_argument("--camera-xy", help="the camera on base_link, X,Y metres (default: "
                                        "dataset.json's camera_to_base_link, else 0,0)")
    od.add_argument("--seed", type=int, default=1)
    od.add_argument("--out", help="where to write (default FOLDER/odometry.txt)")
    od.set_defaults(fn=cmd_odometry)

    ch = sub.add_parser("choose", help="choose the pose filter's keys on the validation drives "
                                       "and compare a candidate model with a baseline "
                                       "(the rule: aprt_tools/choose.py)")
    ch.add_argument("--aprt", default="build/release/bin/aprt", help="the aprt binary")
    ch.add_argument("--model", required=True, help="the model whose keys are chosen")
    ch.add_argument("--config", default="config/default.yaml",
                    help="the configuration the grid's keys are set in (default "
                         "config/default.yaml)")
    ch.add_argument("--drives", nargs="+", required=True,
                    help="validation drives (folders with odometry.txt); never test drives")
    ch.add_argument("--data-root", help="folder the drive names are relative to")
    ch.add_argument("--grid", action="append", metavar="KEY=V1,V2",
                    help="a key and its values (repeat for more keys; section.key where a key "
                         "appears twice); no grid: the configuration as it is")
    ch.add_argument("--baseline-model", help="the model to beat (e.g. the shipped one)")
    ch.add_argument("--baseline-set", action="append", metavar="KEY=V",
                    help="the baseline's keys where they differ from --config")
    ch.add_argument("--tolerance", type=float, default=0.05,
                    help="metres a light's worst published median may lose (default 0.05)")
    ch.add_argument("--jobs", type=int, default=2, help="evaluations at once (default 2)")
    ch.add_argument("--json", help="write every point's figures and the verdict here")
    ch.set_defaults(fn=cmd_choose)

    pe = sub.add_parser("plot-eval", help="trajectory and error plot from `aprt eval --csv` files")
    pe.add_argument("csv", nargs="+", help="one or more CSV files (side by side)")
    pe.add_argument("--out", required=True, help="PNG to write")
    pe.add_argument("--labels", help="comma-separated panel titles (default: file names)")
    pe.add_argument("--title")
    pe.add_argument("--dataset", help="a synthetic drive's dataset.json: draw the town's streets")
    pe.add_argument("--published", action="store_true",
                    help="draw the pose that went out (the pose filter's, where eval ran it) "
                         "instead of the model's estimate")
    pe.set_defaults(fn=cmd_plot_eval)

    pt = sub.add_parser("plot-timing", help="latency histogram and time series of `aprt run --timing`")
    pt.add_argument("report", help="the JSON report (its .csv beside it)")
    pt.add_argument("--out", required=True, help="PNG to write")
    pt.set_defaults(fn=cmd_plot_timing)

    pg = sub.add_parser("preprocess-golden", help="frames and expected inputs for the C++ tests")
    pg.add_argument("--out", required=True)
    pg.set_defaults(fn=cmd_preprocess_golden)

    a = p.parse_args(argv)
    a.fn(a)


if __name__ == "__main__":
    main()
