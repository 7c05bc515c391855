"""The user's choices for the director maps, with the paper's names and defaults."""
from __future__ import annotations

from dataclasses import asdict, dataclass

from ..option_table import DEFAULTS, MAP_OPTIONS, OPTIONS
from .director import check_combination


@dataclass(frozen=True)
class MapOptions:
    """XS(wx, ws, xs_op), XSL(wxs, wl, xsl_op), the light map's n and sigma_base, MinBound.

    ``light_n`` / ``light_sigma_base`` of None mean *auto*: derived per light from the
    optical depth between the camera and the light (``core.maps.light_map.auto_parameters``).
    Sigmas are in pixels at 512 px on the longer side.
    """

    wx: float = DEFAULTS["wx"]
    ws: float = DEFAULTS["ws"]
    xs_op: str = DEFAULTS["xs_op"]
    wxs: float = DEFAULTS["wxs"]
    wl: float = DEFAULTS["wl"]
    xsl_op: str = DEFAULTS["xsl_op"]
    light_n: int | None = DEFAULTS["light_n"]
    light_sigma_base: float | None = DEFAULTS["light_sigma_base"]
    minbound: bool = DEFAULTS["minbound"]

    def validate(self) -> "MapOptions":
        """Each value against its option (``core.option_table``), then the pairs of weights
        (not both 0); SettingError naming the first bad one. Returns self."""
        for name in MAP_OPTIONS:
            OPTIONS[name].check(getattr(self, name))
        check_combination(self.wx, self.ws, self.xs_op, ("wx", "ws", "xs_op"))
        check_combination(self.wxs, self.wl, self.xsl_op, ("wxs", "wl", "xsl_op"))
        return self

    def to_dict(self) -> dict:
        out = asdict(self)
        out["light_n"] = "auto" if self.light_n is None else self.light_n
        out["light_sigma_base"] = "auto" if self.light_sigma_base is None else self.light_sigma_base
        return out
