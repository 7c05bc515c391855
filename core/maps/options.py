"""The user's choices for the director maps, with the paper's names and defaults."""
from __future__ import annotations

from dataclasses import asdict, dataclass

import numpy as np

from ..errors import SettingError
from .director import check_combination

#: Bounds of the light map's n and sigma_base (``light_map``): the paper uses up to 20 and 10;
#: eq. 6 with n iterations has about n^3 / 3 Gaussians, and a sigma_base of 100 already
#: spreads a glow over many frames.
MAX_N = 100
MAX_SIGMA_BASE = 100.0


@dataclass(frozen=True)
class MapOptions:
    """XS(wx, ws, xs_op), XSL(wxs, wl, xsl_op), the light map's n and sigma_base, MinBound.

    ``light_n`` / ``light_sigma_base`` of None mean *auto*: derived per light from the
    optical depth between the camera and the light (``core.maps.light_map.auto_parameters``).
    Sigmas are in pixels at 512 px on the longer side.
    """

    wx: float = 0.5
    ws: float = 0.5
    xs_op: str = "add"
    wxs: float = 0.5
    wl: float = 0.5
    xsl_op: str = "add"
    light_n: int | None = None
    light_sigma_base: float | None = None
    minbound: bool = True

    def validate(self) -> "MapOptions":
        check_combination(self.wx, self.ws, self.xs_op, ("wx", "ws", "xs_op"))
        check_combination(self.wxs, self.wl, self.xsl_op, ("wxs", "wl", "xsl_op"))
        n, sigma = self.light_n, self.light_sigma_base
        if n is not None and (int(n) != n or not 0 <= n <= MAX_N):
            raise SettingError(f"{{light_n.name}} must be a whole number from 0 to {MAX_N} or "
                               "'auto', got {light_n.value}", light_n=n)
        if sigma is not None and not (np.isfinite(sigma) and 0 < sigma <= MAX_SIGMA_BASE):
            raise SettingError(f"{{light_sigma_base.name}} must be > 0 and at most "
                               f"{MAX_SIGMA_BASE:g} or 'auto', got {{light_sigma_base.value}}",
                               light_sigma_base=sigma)
        return self

    def to_dict(self) -> dict:
        out = asdict(self)
        out["light_n"] = "auto" if self.light_n is None else self.light_n
        out["light_sigma_base"] = "auto" if self.light_sigma_base is None else self.light_sigma_base
        return out
