"""The director maps of sections 4.3 and 4.5: XS(w_x, w_s, op) and XSL(w_xs, w_l, op).

Every input is brought to [0, 1] first (``to_unit_range``) and the result stays in
[0, 1]. The paper uses ``add``, a weighted sum ("all weighted features are preserved");
it mentions a multiplicative operator for "saliency modulated by the decay of light".
We read ``multiply`` as the weighted geometric combination A^w_a * B^w_b, the product
counterpart of the weighted sum: with weights (1, 0) it is A itself, as XS(1, 0, +) is X.
"""
from __future__ import annotations

import numpy as np

from ..errors import SettingError
from ..option_table import OPERATORS



def to_unit_range(values: np.ndarray) -> np.ndarray:
    """A map in [0, 1]: maps already there are kept as they are (X is a physical fraction
    and stretching it would call thin uniform fog important); larger ranges are divided
    by their maximum. NaN never passes."""
    values = np.asarray(values, dtype=np.float32)
    if not np.isfinite(values).all():
        raise ValueError("a director map input has NaN or Inf values")
    values = np.maximum(values, 0.0)
    peak = float(values.max()) if values.size else 0.0
    return values / np.float32(peak) if peak > 1.0 else values


def check_combination(w_a: float, w_b: float, op: str, names: tuple[str, str, str]) -> None:
    """Weights >= 0 (not both 0) and a known operator; ``names`` are the settings' fields
    (``MapOptions``: "wx", "ws", "xs_op"), which the errors name."""
    a, b, operation = names
    for weight, name in zip((w_a, w_b), (a, b)):
        if not np.isfinite(weight) or weight < 0:
            raise SettingError(f"{{{name}.name}} must be a number >= 0, got {{{name}.value}}",
                               **{name: weight})
    if w_a == 0 and w_b == 0:
        raise SettingError(f"{{{a}.name}} and {{{b}.name}} cannot both be 0", **{a: w_a, b: w_b})
    if op not in OPERATORS:
        raise SettingError(f"{{{operation}.name}} must be 'add' or 'multiply', "
                           f"got '{{{operation}.value}}'", **{operation: op})


def combine(a: np.ndarray, b: np.ndarray, w_a: float, w_b: float, op: str = "add",
            names: tuple[str, str, str] = ("w_a", "w_b", "op")) -> np.ndarray:
    """w_a A (op) w_b B in [0, 1], float32.

    ``add``: w_a A + w_b B, divided by w_a + w_b when the weights sum to more than one.
    ``multiply``: A^w_a * B^w_b.
    """
    check_combination(w_a, w_b, op, names)
    a, b = to_unit_range(a), to_unit_range(b)
    if a.shape != b.shape:
        raise ValueError(f"maps of different shapes: {a.shape} and {b.shape}")
    if op == "add":
        out = np.float32(w_a) * a + np.float32(w_b) * b
        total = w_a + w_b
        if total > 1.0:
            out = out / np.float32(total)
    else:
        out = np.power(a, np.float32(w_a)) * np.power(b, np.float32(w_b))
    return np.clip(out, 0.0, 1.0).astype(np.float32)


def xs_map(x_map: np.ndarray, s_map: np.ndarray, w_x: float = 0.5, w_s: float = 0.5,
           op: str = "add") -> np.ndarray:
    """XS(w_x, w_s, op) of section 4.3; the paper's XS map is XS(0.5, 0.5, +)."""
    return combine(x_map, s_map, w_x, w_s, op, names=("wx", "ws", "xs_op"))


def xsl_map(xs: np.ndarray, l_map: np.ndarray, w_xs: float = 0.5, w_l: float = 0.5,
            op: str = "add") -> np.ndarray:
    """XSL(w_xs, w_l, op) of section 4.5; the paper's XSL map is XSL(0.5, 0.5, +)."""
    return combine(xs, l_map, w_xs, w_l, op, names=("wxs", "wl", "xsl_op"))
