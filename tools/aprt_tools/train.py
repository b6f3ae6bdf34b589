"""Training of the reference APR-Transformer on a labelled sequence (CPU).

The paper's loss (Kendall et al.'s learned weighting): L = L_p exp(-s_x) + s_x
+ L_q exp(-s_q) + s_q, with L1 position error on min-max normalised positions
and a sign-invariant L1 quaternion error (q and -q are one rotation); Adam.
Colour augmentation (brightness, contrast, per-channel gain, gamma, haze,
noise) stands in for the lighting the training sequences do not show. The
validation error that the model file records comes from a separate drive
(`val`) or, without one, from a contiguous tenth of the route held out; the
test sequence is never looked at here.

  python3 -m aprt_tools train --data DIR [DIR ...] [--val DIR] --out DIR [--size 128] ...
"""

from __future__ import annotations

import json
import math
import os
import time

import numpy as np
import torch
from torch import nn

from .dataset import orientation_error_deg
from .model.apr_transformer import AprConfig, AprTransformer
from .preprocess import normalise
from .train_data import _load, augment, network_input, split_holdout
from .train_loss import PoseLoss
from .train_resume import SAVE_EVERY_S, STOP_FILE, record


@torch.no_grad()
def evaluate(model, imgs, pos, quat, lo, hi, batch=32, mean=None, std=None):
    model.eval()
    pe, oe = [], []
    for i in range(0, len(imgs), batch):
        x = network_input(imgs[i:i + batch], model.cfg)
        y = model(x)
        p = y[:, :3] * (hi - lo) + lo
        for k in range(len(p)):
            pe.append(float(torch.norm(p[k] - pos[i + k])))
            oe.append(orientation_error_deg(y[k, 3:7].numpy(), quat[i + k].numpy()))
    model.train()
    return np.array(pe), np.array(oe)


def train(data, out: str, size: int = 128, minutes: float = 90.0, batch: int = 16,
          lr: float = 1e-4, seed: int = 1, threads: int = 2, hidden: int = 128, layers: int = 3,
          warmup_steps: int = 200, modality: str = "image", config: AprConfig | None = None,
          inputs: str | None = None, inputs_every: int = 1, val: str | None = None,
          augment_from: float = 0.3, init: str | None = None, workers: int = 1,
          uncertainty: bool = False, ema: float = 0.0, resize: int | None = None,
          bev_span_m: float = 32.0, chroma: bool = False, log=print,
          resume: tuple | None = None):
    """data: one sequence folder or a list of them (several drives, e.g. under
    different light), trained on together. val: a separate drive whose errors
    are reported each epoch and recorded as the model's `val_error`; without
    it a contiguous tenth of the (first) route is held out instead.
    augment_from: the fraction of the budget before colour augmentation starts
    ramping in (it reaches full strength 0.4 later). chroma: the augmentation
    also turns hue and saturation (train_data.augment).
    init: a checkpoint.pth this trainer wrote, or a model file (.aprt, fp32)
    converted from one; training continues from its weights (and a
    checkpoint's learned loss weights), with its configuration and position
    bounds (a second phase, or fine-tuning on new drives). The learning-rate
    schedule and the augmentation curriculum start again over `minutes`.
    uncertainty: add the confidence heads (AprConfig.uncertainty) if the
    configuration has none; they learn the pose's error scales (uncertainty_nll).
    resize: with `init` on an image model, train at this input side instead
    of the initial model's (e.g. 64 -> 96): every convolution and the
    transformer carry over unchanged; the learned position tables are
    stretched to the larger feature maps (stretch_position_tables).
    resume: (checkpoint, record) from train_resume.load: continue that run
    where it stopped (train_resume.resume builds the call).
    ema: keep an exponential moving average of the weights with this decay per
    step (e.g. 0.999) and evaluate, save and export it; 0: the weights as trained.
    workers: data-parallel processes sharing `threads` (the batch is split
    between them); 2 with threads 2 is the fastest on two cores.

    modality "image": DATA's poses.txt + images at size x size; "bev": its
    lidar_poses.txt + scans as size x size BEV histograms over a square of
    bev_span_m (default 32: the 'bev' configuration's geometry at that grid;
    cells of bev_span_m / size); "points": the same scans as
    `size` farthest-point samples through PointNet++ (the 'points'
    configuration; size >= 1024). LiDAR without augmentation.

    config: a whole configuration instead of the preset (`python3 -m aprt_tools
    config NAME` writes one to edit: BEV cell size, height threshold and clip
    count; the points crop, sample count, levels and token grid; the
    transformer); its modality and size win over `modality`, `size`,
    `hidden` and `layers`."""
    torch.manual_seed(seed)
    torch.set_num_threads(threads)
    os.makedirs(out, exist_ok=True)
    t0 = time.time()
    checkpoint = None
    if resume is not None:
        if init is not None or config is not None:
            raise ValueError("a resumed run keeps its own weights and configuration: no --init "
                             "or --config-json with --resume")
        checkpoint = resume[0]
        config = AprConfig.from_json(json.dumps(checkpoint["config"]))
        file_size = config.image_size
    elif init is not None:
        if config is not None:
            raise ValueError("give either a configuration or a checkpoint to start from, not both")
        checkpoint = _load_init(init, log)
        config = AprConfig.from_json(json.dumps(checkpoint["config"]))
        file_size = config.image_size
        if resize is not None and resize != file_size:
            if config.points or config.bev:
                raise ValueError("--size with --init changes an image model's input only")
            side = 8 * config.pos_embed_cells
            if resize % 32 or resize > side:
                raise ValueError(f"input side {resize}: must be a multiple of 32 and at most "
                                 f"{side} (the position tables' reach)")
            log(f"train: input {file_size} -> {resize} (weights of the {file_size} model)")
            config.image_size = resize
    if config is not None:
        cfg = AprConfig.from_json(config.to_json())
        modality = "points" if cfg.points else "bev" if cfg.bev else "image"
        size = cfg.image_size
        hidden, layers = cfg.hidden_dim, cfg.enc_layers
    else:
        cfg = AprConfig.named({"bev": "bev", "points": "points"}.get(modality, "full"), size,
                              bev_span_m)
    folders = [data] if isinstance(data, str) else list(data)
    if not folders:
        raise ValueError("no training sequence given")
    if workers < 1 or batch % workers:
        raise ValueError(f"batch {batch} does not split over {workers} workers")
    if modality == "points":
        from .model.pointnet2 import check_points_config

        check_points_config(cfg.points)
        if inputs and len(folders) > 1:
            raise ValueError("--inputs holds one sequence's inputs; give one --data with it")
    imgs, pos, quat = _load(folders, modality, size, cfg, log, inputs, inputs_every)
    log(f"train: {len(imgs)} frames from {', '.join(folders)} loaded in {time.time() - t0:.0f} s")
    if val:
        v_imgs, v_pos, v_quat = _load([val], modality, size, cfg, log, None, 1)
        tr = np.arange(len(imgs))
        log(f"train: validation drive {val}: {len(v_imgs)} frames")
    else:
        tr, va = split_holdout(len(imgs))
        v_imgs, v_pos, v_quat = imgs[va], pos[va], quat[va]
    if resume is not None and len(tr) != resume[1]["frames"]:
        raise ValueError(f"the run trained on {resume[1]['frames']} frames of {', '.join(folders)}"
                         f", which now hold {len(tr)}: its drives changed, so it cannot be resumed "
                         "(--init starts a new schedule from its weights)")
    if checkpoint is not None:  # the head regresses within the bounds it was trained with
        lo, hi = torch.tensor(cfg.pose_min), torch.tensor(cfg.pose_max)
    else:
        lo = pos[tr].min(dim=0).values
        hi = pos[tr].max(dim=0).values
        hi = torch.maximum(hi, lo + 1.0)  # a flat axis (camera height) still gets a unit range
    if config is None:
        cfg.hidden_dim, cfg.dim_feedforward = hidden, 2 * hidden
        cfg.enc_layers = cfg.dec_layers = layers
    cfg.dropout = 0.0  # the augmentation regularises; dropout slowed the start further
    cfg.pose_min, cfg.pose_max = tuple(lo.tolist()), tuple(hi.tolist())
    had_heads = cfg.uncertainty
    cfg.uncertainty = cfg.uncertainty or uncertainty
    model = AprTransformer(cfg)
    loss_fn = PoseLoss()
    if checkpoint is not None:
        state = checkpoint["model_state_dict"]
        if resume is not None:  # the weights as trained; their average goes to _fit
            state = checkpoint.get("train_state_dict", state)
        if "bn_frames" in checkpoint:  # a model file: its BatchNorm re-estimated on these frames
            state = _model_file_state(checkpoint, imgs[tr], cfg, file_size, log)
        if cfg.image_size != file_size:
            state = stretch_position_tables(state, file_size, cfg.image_size)
        missing, unexpected = model.load_state_dict(state, strict=False)
        if unexpected or any(not (k.startswith("uncertainty_head") and not had_heads)
                             for k in missing):
            raise ValueError(f"{init}: weights do not fit the network (missing {missing[:3]}, "
                             f"unexpected {unexpected[:3]})")
        loss_fn = PoseLoss(checkpoint.get("s_x", -3.0), checkpoint.get("s_q", -3.0))
        if resume is None:
            log(f"train: continuing from {init}" + (" (new confidence heads)" if missing else ""))
    pos_n = (pos - lo) / (hi - lo)
    plan = dict(cfg=cfg.to_json(), lo=lo, hi=hi, lr=lr, batch=batch, seed=seed, ema=ema,
                warmup_steps=warmup_steps, budget=minutes * 60.0, augment_from=augment_from,
                chroma=chroma, modality=modality, out=out, folders=folders, val=val, tr=tr,
                threads=max(1, threads // workers),
                # What train_resume needs to call train() again for this run.
                # Paths absolute: a run is resumed from any working directory.
                args=dict(data=[os.path.abspath(f) for f in folders], batch=batch, lr=lr, seed=seed, threads=threads,
                          warmup_steps=warmup_steps, modality=modality,
                          inputs=inputs and os.path.abspath(inputs),
                          inputs_every=inputs_every, val=val and os.path.abspath(val),
                          augment_from=augment_from,
                          workers=workers, uncertainty=uncertainty, ema=ema,
                          bev_span_m=bev_span_m, chroma=chroma))
    if resume is not None:
        plan["resume"] = dict(resume[1], averaged=checkpoint["model_state_dict"])
    data = (imgs, pos_n, quat, v_imgs, v_pos, v_quat)
    stale = os.path.join(out, "best.pth")
    if resume is None and os.path.exists(stale):  # an earlier run's into the same folder
        os.remove(stale)
    if workers == 1:
        _fit(0, 1, plan, data, model, loss_fn, log)
    else:
        _fit_in_workers(workers, plan, data, model, loss_fn)
    # The best validation point's weights (or their average with --ema);
    # checkpoint.pth keeps the last, to continue from.
    best = os.path.join(out, "best.pth")
    final = torch.load(best if os.path.exists(best) else os.path.join(out, "checkpoint.pth"),
                       map_location="cpu")
    if "epoch" in final:
        log(f"train: exporting the best validation point: epoch {final['epoch']}, "
            f"median {final['val_pos_median']:.2f} m")
    model.load_state_dict(final["model_state_dict"])
    cfg.dropout = 0.0
    return model, cfg


def stretch_position_tables(state: dict, old_side: int, new_side: int) -> dict:
    """The learned position tables of a model trained at input side
    old_side, resampled for new_side (the usual way a transformer's learned
    positions follow a change of resolution: Dosovitskiy et al. 2021, sec. 3.2).
    Row k of a feature map of n cells covers the image around (k + 0.5) / n,
    so the new row k reads the old table at (k + 0.5) * old / new - 0.5,
    linearly between the two nearest rows. The two feature maps (side / 16 and
    side / 8) share the tables and scale by the same factor, so one
    resampling serves both; rows beyond the finer map's reach are kept."""
    state = dict(state)
    n_old, n_new = old_side // 8, new_side // 8
    for key in ("backbone.1.row_embed.weight", "backbone.1.col_embed.weight"):
        table = state[key].clone()
        if n_new > table.shape[0]:
            raise ValueError(f"input side {new_side} needs {n_new} position cells, the tables "
                             f"have {table.shape[0]}")
        old = state[key][:n_old]
        src = ((torch.arange(n_new, dtype=torch.float64) + 0.5) * old_side / new_side - 0.5)
        src = src.clamp(0, n_old - 1)
        lo = src.floor().long().clamp(max=n_old - 1)
        hi = (lo + 1).clamp(max=n_old - 1)
        w = (src - lo.double()).unsqueeze(1).to(table.dtype)
        table[:n_new] = old[lo] * (1 - w) + old[hi] * w
        state[key] = table
    return state


def _load_init(init: str, log) -> dict:
    """A checkpoint this trainer wrote, or a model file (read back with
    model_bin.to_torch; its BatchNorm is re-estimated on training frames
    once they are loaded: see _model_file_state)."""
    with open(init, "rb") as f:
        head = f.read(8)
    if head == b"APRTMDL\x00":
        from .model_bin import reader
        from .model_bin.to_torch import config_of

        data = open(init, "rb").read()
        _, meta = reader.read(data)
        cfg = config_of(meta)
        log(f"train: starting from the model file {init}")
        return {"model_state_dict": None, "config": json.loads(cfg.to_json()), "bn_frames": True,
                "model_file": data}
    checkpoint = torch.load(init, map_location="cpu")
    if not isinstance(checkpoint, dict) or "model_state_dict" not in checkpoint:
        raise ValueError(f"{init}: neither a checkpoint written by aprt_tools train nor a model "
                         "file")
    return checkpoint


def _model_file_state(checkpoint: dict, frames: torch.Tensor, cfg, file_size: int, log) -> dict:
    """The model file's network, its BatchNorm statistics estimated on 64 of
    the training frames (brought to the file's input side); checked against
    the file's own graph."""
    from .model_bin import to_torch

    pick = torch.linspace(0, len(frames) - 1, 64).long()
    x = network_input(frames[pick], cfg)
    if x.shape[-1] != file_size:
        x = torch.nn.functional.interpolate(x, size=(file_size, file_size), mode="area")
    model, _ = to_torch.load(checkpoint["model_file"], x)
    worst = to_torch.check(checkpoint["model_file"], model, x[:4])
    if worst > 1e-3:
        raise ValueError(f"the model file read back differs from its graph by {worst:.2g} "
                         "(relative): not continuing from a different network")
    log(f"train: model file read back (largest relative difference {worst:.1e})")
    return model.state_dict()


class _Objective(nn.Module):
    """The network and its loss as one module, so that data-parallel workers
    average the learned loss weights' gradients along with the network's."""

    def __init__(self, model: nn.Module, loss_fn: nn.Module):
        super().__init__()
        self.model, self.loss_fn = model, loss_fn

    def forward(self, x, pos, quat):
        return self.loss_fn(self.model(x), pos, quat)


def _fit_in_workers(workers: int, plan: dict, data: tuple, model, loss_fn):
    """Data-parallel training in `workers` processes of plan["threads"] threads
    each (gloo, gradients averaged every step): on small CPU tensors two
    one-thread processes do ~1.4x the frames per second of one two-thread
    process, whose second thread mostly waits. The frames go to the workers as
    memory-mapped .npy files (no shared-memory limit), the initial weights as
    a state dict; rank 0 evaluates, logs and writes the checkpoints."""
    import tempfile

    import torch.multiprocessing as mp

    with tempfile.TemporaryDirectory(dir=plan["out"], prefix=".workers-") as tmp:
        for k, t in enumerate(data):
            np.save(os.path.join(tmp, f"{k}.npy"), t.numpy())
        # The resume state (the optimiser's moments: twice the weights) goes
        # by file like the weights, not through the spawn's pickled arguments.
        plan = dict(plan)
        torch.save({"model": model.state_dict(), "loss": loss_fn.state_dict(),
                    "resume": plan.pop("resume", None)}, os.path.join(tmp, "init.pth"))
        mp.spawn(_worker, args=(workers, plan, tmp), nprocs=workers, join=True)


def _worker(rank: int, world: int, plan: dict, tmp: str):
    import torch.distributed as dist

    torch.set_num_threads(plan["threads"])
    dist.init_process_group("gloo", init_method=f"file://{tmp}/rendezvous", rank=rank,
                            world_size=world)
    data = tuple(torch.from_numpy(np.load(os.path.join(tmp, f"{k}.npy"), mmap_mode="r+"))
                 for k in range(6))
    init = torch.load(os.path.join(tmp, "init.pth"))
    model, loss_fn = AprTransformer(AprConfig.from_json(plan["cfg"])), PoseLoss()
    model.load_state_dict(init["model"])
    loss_fn.load_state_dict(init["loss"])
    if init["resume"] is not None:
        plan = dict(plan, resume=init["resume"])
    try:
        _fit(rank, world, plan, data, model, loss_fn, lambda line: print(line, flush=True))
    finally:
        dist.destroy_process_group()


def _fit(rank: int, world: int, plan: dict, data: tuple, model, loss_fn, log):
    """The training loop; with world > 1 one data-parallel worker of several:
    each takes its share of every batch, rank 0 decides the schedule (time is
    read once, so every worker takes the same learning rate and stops at the
    same step) and does the evaluation, logging and checkpoints."""
    imgs, pos_n, quat, v_imgs, v_pos, v_quat = data
    cfg = model.cfg
    lo, hi, lr, batch = plan["lo"], plan["hi"], plan["lr"], plan["batch"]
    budget, out, tr = plan["budget"], plan["out"], plan["tr"]
    objective = _Objective(model, loss_fn)
    if world > 1:
        import torch.distributed as dist

        # The trunk keeps EfficientNet's later stages (upstream's layout and
        # checkpoint keys) but never runs them: their parameters get no gradient.
        objective = nn.parallel.DistributedDataParallel(objective, find_unused_parameters=True)
    opt = torch.optim.AdamW(objective.parameters(), lr=lr, weight_decay=1e-4)
    resumed = plan.get("resume")  # a stopped run's state (train_resume)
    if resumed is not None:
        opt.load_state_dict(resumed["optimizer"])
    averaged = None
    if plan.get("ema") and rank == 0:  # every worker holds the same weights: one average
        import copy

        averaged = copy.deepcopy(model)
        averaged.eval()
        if resumed is not None:
            averaged.load_state_dict(resumed["averaged"])
    perm_gen = torch.Generator().manual_seed(plan["seed"])  # the same order in every worker
    aug_gen = torch.Generator().manual_seed(plan["seed"] + 1 + rank)
    start = time.time()
    step, epoch = 0, 0
    log_rows = []
    pending = None  # a resumed epoch's frame order and its first batch not yet trained
    if resumed is not None:
        perm_gen.set_state(resumed["perm_gen"])
        aug_gen.manual_seed(plan["seed"] + 1 + rank + 7919 * resumed["step"])
        start -= resumed["elapsed_s"]
        step, epoch, log_rows = resumed["step"], resumed["epoch"], list(resumed["log_rows"])
        if resumed["perm"] is not None:
            pending = (resumed["perm"], resumed["offset"])
    stop_file = os.path.join(out, STOP_FILE)
    saved_at = time.time()

    def resume_record(perm, offset):
        return record(plan, opt, perm_gen, step, epoch, time.time() - start, perm, offset,
                      log_rows)

    clock = torch.zeros(2, dtype=torch.float64)  # rank 0's time and stop, for every worker
    done = stopped = False
    while not done:
        if pending is not None:
            (perm, first), pending = pending, None
        else:
            epoch += 1
            perm = torch.from_numpy(tr[torch.randperm(len(tr), generator=perm_gen).numpy()])
            first = 0
        unfinished = None  # where this epoch stopped, if it did
        for b in range(first, len(perm) - batch + 1, batch):
            clock[0] = (time.time() - start) / budget
            clock[1] = float(rank == 0 and os.path.exists(stop_file))  # asked to stop
            if world > 1:
                dist.broadcast(clock, 0)
            frac = float(clock[0])
            if frac >= 1.0 or clock[1] > 0:
                done, stopped, unfinished = True, bool(clock[1] > 0), b
                break
            if rank == 0 and time.time() - saved_at > SAVE_EVERY_S:
                _save(out, model, averaged, loss_fn, resume_record(perm, b))
                saved_at = time.time()
            # Linear warm-up (a from-scratch transformer with post-norm diverges at
            # a high rate otherwise), constant, then cosine decay over the last 40 %.
            scale = min(1.0, (step + 1) / plan["warmup_steps"])
            if frac > 0.6:
                scale *= 0.02 + 0.98 * 0.5 * (1 + math.cos(math.pi * (frac - 0.6) / 0.4))
            for g in opt.param_groups:
                g["lr"] = lr * scale
            idx = perm[b:b + batch][rank::world]
            # Curriculum: clean frames first (a from-scratch trunk learns places
            # before it can learn invariance to lighting), augmentation ramped
            # in from 30 % to 70 % of the budget. With full augmentation from the
            # start the position stayed at the mean for 10+ CPU-minutes.
            strength = (min(1.0, max(0.0, (frac - plan["augment_from"]) / 0.4))
                        if plan["modality"] == "image" else 0.0)
            if cfg.points:
                x = imgs[idx]
            else:
                x = augment(imgs[idx].float() / 255.0, aug_gen, strength, plan["chroma"])
                x = normalise(x, cfg.mean, cfg.std)
            loss, lp, lq = objective(x, pos_n[idx], quat[idx])
            opt.zero_grad()
            loss.backward()
            nn.utils.clip_grad_norm_(model.parameters(), 2.0)
            opt.step()
            step += 1
            if averaged is not None:
                _ema_update(averaged, model, plan["ema"], step)
            if step % 50 == 0 and rank == 0:
                log(f"train: epoch {epoch} step {step} loss {loss.item():.3f} pos {lp.item():.4f} "
                    f"quat {lq.item():.4f} s_x {loss_fn.s_x.item():.2f} s_q {loss_fn.s_q.item():.2f} "
                    f"{(time.time() - start) / 60:.1f} min")
        if rank == 0:
            shipped = averaged if averaged is not None else model
            pe, oe = evaluate(shipped, v_imgs, v_pos, v_quat, lo, hi, mean=cfg.mean, std=cfg.std)
            row = dict(epoch=epoch, step=step, minutes=(time.time() - start) / 60,
                       val_pos_median=float(np.median(pe)), val_rot_median=float(np.median(oe)))
            if unfinished is not None:  # the validation point of a stopped or timed-out epoch
                row["partial"] = True
            log_rows.append(row)
            log(f"train: epoch {epoch} done: validation median {row['val_pos_median']:.2f} m, "
                f"{row['val_rot_median']:.2f} deg")
            row["val_pos_p90"] = float(np.percentile(pe, 90))
            row["val_share_over_10m"] = float(np.mean(pe > 10.0))
            saved = _save(out, model, averaged, loss_fn,
                          resume_record(None if unfinished is None else perm, unfinished or 0))
            saved_at = time.time()
            if stopped:
                os.remove(stop_file)
                log(f"train: stopped by {stop_file} at {row['minutes']:.1f} of "
                    f"{budget / 60:.1f} minutes; `train --resume {out}` continues")
            # The best validation point so far is what the run exports: the
            # last one can be worse (the average still moving as the rate decays).
            if row["val_pos_median"] <= min(r["val_pos_median"] for r in log_rows):
                best = {k: v for k, v in saved.items() if k != "resume"}  # weights only
                best["epoch"] = epoch
                best["val_pos_median"] = row["val_pos_median"]
                torch.save(best, os.path.join(out, "best.pth.tmp"))
                os.replace(os.path.join(out, "best.pth.tmp"), os.path.join(out, "best.pth"))
            # Written every epoch: an interrupted run is still exportable
            # (python3 -m aprt_tools export --config-json OUT/model.json --weights
            # OUT/checkpoint.pth -o OUT/model.onnx, then convert).
            _write_config(out, cfg, log_rows, start, tr, epoch, step, plan["folders"], plan["val"])
        if world > 1:
            dist.barrier()
    if world > 1:  # every worker must hold the same weights, or the averaging is broken
        sums = torch.stack([p.detach().double().sum() for p in objective.parameters()])
        gathered = [torch.zeros_like(sums) for _ in range(world)]
        dist.all_gather(gathered, sums)
        if any(not torch.equal(g, gathered[0]) for g in gathered):
            raise RuntimeError("train: the workers' weights diverged")


def _save(out: str, model, averaged, loss_fn, resume: dict) -> dict:
    """checkpoint.pth, replaced whole: the weights shipped (the average with
    --ema), the weights as trained, the loss weights and the resume record."""
    shipped = averaged if averaged is not None else model
    saved = {"model_state_dict": shipped.state_dict(), "config": json.loads(model.cfg.to_json()),
             "s_x": loss_fn.s_x.item(), "s_q": loss_fn.s_q.item(), "resume": resume}
    if averaged is not None:  # to continue training from the weights as trained
        saved["train_state_dict"] = model.state_dict()
    torch.save(saved, os.path.join(out, "checkpoint.pth.tmp"))
    os.replace(os.path.join(out, "checkpoint.pth.tmp"), os.path.join(out, "checkpoint.pth"))
    return saved


@torch.no_grad()
def _ema_update(averaged: nn.Module, model: nn.Module, decay: float, step: int):
    """Polyak averaging; the decay ramps up over the first steps so that the
    average starts from the weights, not from their initial values.
    BatchNorm's running statistics are copied (they are averages already)."""
    d = min(decay, (1.0 + step) / (10.0 + step))
    for a, p in zip(averaged.parameters(), model.parameters()):
        a.mul_(d).add_(p.detach(), alpha=1.0 - d)
    for a, b in zip(averaged.buffers(), model.buffers()):
        a.copy_(b)


def _write_config(out, cfg, log_rows, start, tr, epoch, step, folders, val):
    final = AprConfig.from_json(cfg.to_json())
    final.dropout = 0.0
    best = min(log_rows, key=lambda r: r["val_pos_median"])  # what best.pth holds
    final.extra = dict(val_error=[best["val_pos_median"], best["val_rot_median"]],
                       train_minutes=(time.time() - start) / 60, train_frames=int(len(tr)),
                       epochs=epoch, steps=step,
                       data=",".join(os.path.basename(os.path.abspath(f)) for f in folders),
                       validation=os.path.basename(os.path.abspath(val)) if val else "holdout")
    with open(os.path.join(out, "model.json"), "w") as f:
        f.write(final.to_json())
    with open(os.path.join(out, "train_log.json"), "w") as f:
        json.dump(log_rows, f, indent=1)
