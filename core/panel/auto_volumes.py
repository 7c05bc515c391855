"""What the panel shows of Auto Volumes' choice for the current frame, as lines of text."""
from __future__ import annotations

#: Cycles' volume sampling methods as its interface names them.
SAMPLING_LABELS = {"DISTANCE": "Distance", "EQUIANGULAR": "Equiangular",
                   "MULTIPLE_IMPORTANCE": "Multiple Importance"}


def _name(key: str) -> str:
    """'material:fog' -> "fog", 'world:World' -> "World (world)"."""
    kind, name = key.split(":", 1)
    return f"{name} (world)" if kind == "world" else name


def preview_lines(choice, shot: tuple[int, int], frame: int, frames: tuple[int, ...]) -> list[str]:
    """The lines for an ``EstimatorChoice`` made for ``shot``, decided at ``frame`` of the
    sampled ``frames``: the estimator and step, each medium's own step and volume sampling,
    the light tree and sample pattern, the predicted error, or why the file's settings stay."""
    first, last = shot
    lines = [f"Frames {first}-{last}: decided at frame {frame} of {', '.join(map(str, frames))}"
             if first != last else f"Frame {first} (outside the file's range)"]
    if choice.biased is None:
        lines.append("Volumes: the file's own settings (" + (choice.reason or "nothing to choose") + ")")
    elif not choice.biased:
        lines.append("Volumes: null scattering (unbiased)")
    else:
        rate = "the file's step rate" if choice.step_rate is None else f"step rate {choice.step_rate:g}"
        lines.append(f"Volumes: ray marching at {rate}")
    for key, rate in (choice.medium_rates or {}).items():
        lines.append(f"  {_name(key)}: its own step, as at rate {rate:g}")
    if choice.biased:
        for key, method in (choice.scatter_sampling or {}).items():
            lines.append(f"  {_name(key)}: {SAMPLING_LABELS.get(method, method)} sampling")
    if choice.predicted_bias is not None and choice.tolerance is not None:
        lines.append(f"Predicted error {choice.predicted_bias:.2%} (the noise hides {choice.tolerance:.2%})")
    if choice.light_tree is False:
        lines.append("Light tree: off (one light)")
    if choice.sample_pattern is not None:
        lines.append(f"Sample pattern: {choice.sample_pattern.replace('_', ' ').title()}")
    return lines
