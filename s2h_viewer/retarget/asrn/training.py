"""`s2h train`: the paper's semi-supervised training of ASRN (or DM) on the procedural training hands.

Loss per batch (DESIGN.md section 5): ``1[A = B] MSE(Q_A, Q_B) - lambda_sem L_sem + lambda_ana L_ana``
with the paper's (1.0, 0.1) as `TrainConfig`'s defaults. DM replaces L_sem by the mean squared
difference of the two distance matrices. The shipped ASRN (`SHIPPED`) goes beyond the paper: a contact
loss over the fingertip pad pairs (`contact_loss`: pads touching in the source touch on the target,
pads apart stay apart), because L_sem alone lets a few millimetres open between pads that must touch,
L_ana weighted 1.0 so that the pull toward contacts does not buy them with broken limits, and half
the batches supervised (A = B) so that a hand retargeted onto itself stays itself, and beside the gesture
scripts as many clips through random key poses over the whole pose space (`motions.pose_space`), since
real hands make poses the 31 gestures do not.
Fingertip-on-palm pairs are left to L_sem: on long-fingered hands the palm is out of reach within
the bend limits. The shipped DM, the baseline of Zhang et al., keeps the paper's loss.
The learning rate follows a cosine decay to zero (computed from the step, so resuming needs no
scheduler state); without it the last steps could jump to a much worse model.
Seeded; checkpoints (atomic) every ``checkpoint_every`` steps and at the end. The checkpoint holds
the model and how it was trained (small, shipped); the optimiser and random states go beside it in
``<name>.resume.pt`` (not shipped), from which ``resume`` continues exactly.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import torch
from tqdm import tqdm

from s2h_viewer.errors import InputFileError
from s2h_viewer.hand.kinematics import forward_kinematics
from s2h_viewer.hand.model import HandModel
from s2h_viewer.io.atomic import atomic_path
from s2h_viewer.retarget.asrn.dataset import (Batch, TrainingSet, build_training_set, extra_training_hands,
                                              sample_batch)
from s2h_viewer.retarget.asrn.features import SEMANTIC_SIZE, feature_size, semantic_features
from s2h_viewer.retarget.asrn.model import RetargetNet, apply_residual
from s2h_viewer.semantics.anatomy import anatomical_loss
from s2h_viewer.semantics.contacts import PAD_PAIRS, contact_loss, pad_pair_gaps
from s2h_viewer.semantics.similarity import semantic_similarity

GRADIENT_CLIP = 1.0
DM_LOSS_SCALE = 10.0  # brings the distance-matrix MSE to the size of the ASM similarity term


@dataclass(frozen=True)
class TrainConfig:
    kind: str = "asrn"
    steps: int = 4000
    batch_size: int = 8
    window: int = 32  # about a second at 30 fps (the official net sees 8 frames at 5 fps)
    learning_rate: float = 1e-3
    p_same: float = 0.25
    semantic_weight: float = 1.0
    anatomy_weight: float = 0.1
    contact_weight: float = 0.0  # on pad gaps in hand lengths
    scripts_per_hand: int = 6
    pose_scripts_per_hand: int = 0  # clips through random key poses (motions.pose_space) per hand, beside the scripts
    extra_hands: int = 16  # unnamed procedural hands (seeds disjoint from the shipped ones) for variety
    width: int = 128
    seed: int = 0
    checkpoint_every: int = 500


#: how the shipped networks were trained, beyond `TrainConfig`'s (the paper's) defaults
SHIPPED: dict[str, dict] = {"asrn": {"contact_weight": 300.0, "anatomy_weight": 1.0, "p_same": 0.5,
                                     "pose_scripts_per_hand": 6, "steps": 12000}, "dm": {}}


def default_config(kind: str, **changes) -> TrainConfig:
    """The shipped network's configuration for ``kind``, with ``changes``."""
    return TrainConfig(kind=kind, **SHIPPED[kind] | changes)


def stored_config(state: dict) -> TrainConfig:
    """The configuration a checkpoint was trained with (one from before the contact term or the random
    poses had none)."""
    return TrainConfig(**{"contact_weight": 0.0, "pose_scripts_per_hand": 0} | state["config"])


def build_model(config: TrainConfig) -> RetargetNet:
    return RetargetNet(feature_size(config.kind), width=config.width)


def learning_rate(config: TrainConfig, step: int) -> float:
    """Cosine decay from ``config.learning_rate`` at step 0 to 0 at ``config.steps``."""
    return 0.5 * config.learning_rate * (1.0 + np.cos(np.pi * min(step / config.steps, 1.0)))


def batch_loss(model: RetargetNet, data: TrainingSet, batch: Batch, config: TrainConfig
               ) -> tuple[torch.Tensor, dict[str, float]]:
    """The training loss of one batch and its parts (for the progress bar and history)."""
    hand = data.hands[batch.target]
    shape, frames = (s.expand(len(batch.features), *s.shape) for s in data.statics[batch.target])
    q_pred = apply_residual(batch.q_source, model(batch.features, shape, frames))
    pose = forward_kinematics(hand, q_pred.reshape(-1, 15, 4))
    source_sem = batch.features[..., :SEMANTIC_SIZE[config.kind]].reshape(-1, SEMANTIC_SIZE[config.kind])
    target_sem = semantic_features(config.kind, pose)
    if config.kind == "asrn":
        shape3 = (-1, 20, 29, 3)
        semantic = -semantic_similarity(source_sem.reshape(shape3), target_sem.reshape(shape3))
    else:
        semantic = DM_LOSS_SCALE * (source_sem - target_sem).square().mean()
    mse = (q_pred - batch.q_source).square().mean() if batch.same else q_pred.new_zeros(())
    anatomy = anatomical_loss(q_pred.reshape(-1, 15, 4))
    loss = mse + config.semantic_weight * semantic + config.anatomy_weight * anatomy
    parts = {"loss": loss, "mse": mse, "semantic": semantic, "anatomy": anatomy}
    if config.contact_weight:
        gaps = pad_pair_gaps(hand, pose.positions, thumb_tips=False) / hand.hand_length  # as its data's
        parts["contact"] = contact_loss(gaps, batch.source_gaps.reshape(len(gaps), -1)[:, PAD_PAIRS])
        loss = parts["loss"] = loss + config.contact_weight * parts["contact"]
    return loss, {k: v.item() for k, v in parts.items()}


def resume_path(path: Path) -> Path:
    """Where the optimiser and random states of the checkpoint at ``path`` are kept."""
    return path.with_suffix(".resume.pt")


def save_checkpoint(path: Path, model: RetargetNet, optimiser: torch.optim.Optimizer, config: TrainConfig,
                    step: int, rng: np.random.Generator, history: list[dict], hand_names: list[str]) -> None:
    state = {"format": "s2h-retarget-net", "version": 1, "config": dataclasses.asdict(config), "step": step,
             "model": model.state_dict(), "history": history, "train_hands": hand_names}
    training = {"step": step, "optimiser": optimiser.state_dict(), "numpy_rng": rng.bit_generator.state,
                "torch_rng": torch.get_rng_state()}
    with atomic_path(resume_path(path)) as tmp:
        torch.save(training, tmp)
    with atomic_path(path) as tmp:
        torch.save(state, tmp)


def load_checkpoint(path: str | Path) -> dict:
    """A checkpoint's contents; an `InputFileError` naming the file if it is not one."""
    path = Path(path)
    if not path.exists():
        raise InputFileError(path, "checkpoint not found (train one with `s2h train`)")
    try:
        state = torch.load(path, map_location="cpu", weights_only=False)
    except Exception as exc:  # torch raises many types for a damaged file
        raise InputFileError(path, f"not a readable checkpoint ({type(exc).__name__}: {exc})") from None
    if not isinstance(state, dict) or state.get("format") != "s2h-retarget-net":
        raise InputFileError(path, "not an s2h retargeting-network checkpoint")
    return state


def train(config: TrainConfig, hands: list[HandModel], out: str | Path, resume: bool = False,
          show_progress: bool = True, stop_at: int | None = None) -> list[dict]:
    """Train (or resume) on ``hands`` plus ``config.extra_hands`` procedural ones and write the checkpoint
    to ``out``; ``stop_at`` ends this run early at that step (continue later with ``resume``).
    Returns the loss history (per 100 steps)."""
    out = Path(out)
    last = min(stop_at or config.steps, config.steps)
    torch.manual_seed(config.seed)
    rng = np.random.default_rng(config.seed)
    model = build_model(config)
    optimiser = torch.optim.Adam(model.parameters(), lr=config.learning_rate)
    step, history = 0, []
    if resume and out.exists():
        state = load_checkpoint(out)
        if stored_config(state) != dataclasses.replace(config, steps=state["config"]["steps"]):
            raise InputFileError(out, "checkpoint was trained with a different configuration; cannot resume")
        try:
            training = torch.load(resume_path(out), map_location="cpu", weights_only=False)
        except FileNotFoundError:
            raise InputFileError(resume_path(out), "no optimiser state to resume from") from None
        if training["step"] != state["step"]:
            raise InputFileError(resume_path(out), f"is from step {training['step']}, the checkpoint from "
                                                   f"step {state['step']}")
        model.load_state_dict(state["model"])
        optimiser.load_state_dict(training["optimiser"])
        rng.bit_generator.state = training["numpy_rng"]
        torch.set_rng_state(training["torch_rng"])
        step, history = state["step"], state["history"]
    hands = hands + extra_training_hands(config.extra_hands, config.seed)
    with tqdm(total=len(hands), desc=f"{config.kind} data", disable=not show_progress, leave=False) as bar:
        data = build_training_set(config.kind, hands, config.scripts_per_hand, seed=config.seed,
                                  progress=lambda what: (bar.set_postfix_str(what), bar.update()),
                                  pose_scripts_per_hand=config.pose_scripts_per_hand)
    names = [h.name for h in hands]
    running: list[dict] = []
    skipped = history[-1]["skipped"] if history else 0
    with tqdm(total=config.steps, initial=step, desc=f"train {config.kind}", disable=not show_progress) as bar:
        while step < last:
            batch = sample_batch(data, rng, config.batch_size, config.window, config.p_same)
            loss, parts = batch_loss(model, data, batch, config)
            for group in optimiser.param_groups:
                group["lr"] = learning_rate(config, step)
            optimiser.zero_grad()
            loss.backward()
            grad_norm = torch.nn.utils.clip_grad_norm_(model.parameters(), GRADIENT_CLIP)
            step += 1
            if torch.isfinite(loss) and torch.isfinite(grad_norm):
                optimiser.step()
                running.append(parts)
            else:  # a rare degenerate pose (gimbal lock in the Euler angles of L_ana): skip, never poison Adam
                skipped += 1
            if step % 100 == 0 and running:
                history.append({"step": step, "skipped": skipped,
                                **{k: float(np.mean([r[k] for r in running])) for k in running[0]}})
                bar.set_postfix(loss=f"{history[-1]['loss']:.4f}", semantic=f"{history[-1]['semantic']:.4f}")
                running = []
            bar.update()
            if step % config.checkpoint_every == 0 or step == last:
                save_checkpoint(out, model, optimiser, config, step, rng, history, names)
    return history
