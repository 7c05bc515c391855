"""Draw Blender panels and menus headlessly: a stand-in for ``UILayout`` that records what a
``draw()`` asks for and checks it against RNA (a property that does not exist, an operator
that is not registered or an operator property it does not have, a keyword argument or an
icon the real ``UILayout`` does not take fails at once)."""
from __future__ import annotations

from types import SimpleNamespace


class OperatorCall:
    """What ``layout.operator()`` returns: assignments must be the operator's properties."""

    def __init__(self, bpy, idname: str, log: list, text: str | None = None):
        category, name = idname.split(".")
        operator = getattr(getattr(bpy.ops, category), name)
        rna = operator.get_rna_type()                       # raises for an unknown operator
        object.__setattr__(self, "_names", set(rna.properties.keys()))
        object.__setattr__(self, "idname", idname)
        object.__setattr__(self, "text", text)              # the button's label, if given
        object.__setattr__(self, "values", {})
        log.append(("operator", idname, self))

    def __setattr__(self, name, value):
        if name not in self._names:
            raise AttributeError(f"operator {self.idname} has no property '{name}'")
        self.values[name] = value


class StubLayout:
    def __init__(self, bpy, log: list):
        self._bpy, self.log = bpy, log
        self.active = self.enabled = True
        self.use_property_split = self.use_property_decorate = False
        # Read and set back by the draw functions ``Panel.prepend`` / ``append`` add.
        self.operator_context = "INVOKE_DEFAULT"

    def _check(self, function: str, kwargs: dict) -> None:
        """The keywords (and icon) the real UILayout.<function> accepts."""
        parameters = self._bpy.types.UILayout.bl_rna.functions[function].parameters
        unknown = set(kwargs) - set(parameters.keys())
        if unknown:
            raise TypeError(f"UILayout.{function}() takes no {sorted(unknown)}")
        if "icon" in kwargs and kwargs["icon"] not in parameters["icon"].enum_items.keys():
            raise TypeError(f"no icon {kwargs['icon']}")

    def _child(self, function: str):
        def make(**kwargs) -> "StubLayout":
            self._check(function, kwargs)
            return StubLayout(self._bpy, self.log)
        return make

    def __getattr__(self, name: str):
        if name in ("row", "column", "box", "split", "grid_flow", "column_flow"):
            return self._child(name)
        raise AttributeError(name)

    def prop(self, data, name: str, **kwargs) -> None:
        self._check("prop", kwargs)
        if name not in data.bl_rna.properties.keys():
            raise AttributeError(f"{data.bl_rna.identifier} has no property '{name}'")
        self.log.append(("prop", data, name) + ((kwargs["text"],) if "text" in kwargs else ()))

    def operator(self, idname: str, **kwargs) -> OperatorCall:
        self._check("operator", kwargs)
        return OperatorCall(self._bpy, idname, self.log, kwargs.get("text"))

    def menu(self, idname: str, **kwargs) -> None:
        self._check("menu", kwargs)
        if not hasattr(self._bpy.types, idname):
            raise AttributeError(f"no menu {idname}")
        self.log.append(("menu", idname))

    def label(self, **kwargs) -> None:
        self._check("label", kwargs)
        self.log.append(("label", kwargs.get("text", "")))

    def progress(self, **kwargs) -> None:
        self._check("progress", kwargs)
        self.log.append(("progress", kwargs.get("factor"), kwargs.get("text")))

    def separator(self, **kwargs) -> None:
        self._check("separator", kwargs)


def draw(bpy, cls, context, method: str = "draw") -> list:
    """Run ``cls.<method>`` (draw, draw_header, draw_header_preset) on a stub; the log."""
    log: list = []
    getattr(cls, method)(SimpleNamespace(layout=StubLayout(bpy, log)), context)
    return log
