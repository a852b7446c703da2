"""Built-in temples: Portunus (``portunus.toml``) and the typed presets ``temple_*.toml``.

Each file cites its measurements in its comments; ``[temple] sources`` lists them for
``ionic-usd presets``. No pxr here.
"""

from __future__ import annotations

from importlib import resources
from pathlib import Path

from ionic_usd.errors import ParameterError
from ionic_usd.params import load_toml

__all__ = ["PRESETS", "preset_path", "preset_layout", "preset_summary"]

#: name → packaged file
PRESETS = {
    "portunus": "portunus.toml",
    "priene": "temple_priene.toml",
    "nike": "temple_nike.toml",
    "ilissos": "temple_ilissos.toml",
    "magnesia": "temple_magnesia.toml",
    "ephesus": "temple_ephesus.toml",
    "saturn": "temple_saturn.toml",
}
_PORTUNUS_SOURCES = (
    "Vitruvius, De architectura III–IV",
    "Piranesi's plates (paper ref. [34])",
    "Claridge, Rome: An Oxford Archaeological Guide (2010)",
    "Adam, Roman Building (1994)",
)
_WORDS = {4: "tetrastyle", 6: "hexastyle", 8: "octastyle", 10: "decastyle"}


def preset_path(name: str) -> Path:
    if name not in PRESETS:
        raise ParameterError("--preset", name, "one of " + ", ".join(PRESETS))
    return Path(str(resources.files("ionic_usd") / "data" / PRESETS[name]))


def preset_layout(name: str, *, apply=()):
    from ionic_usd.temple.layout import layout_from_toml

    return layout_from_toml(preset_path(name), apply=apply)


def preset_summary(name: str) -> tuple[str, str, tuple[str, ...]]:
    """(title, type, sources) of a preset."""
    data = load_toml(preset_path(name))
    title = data["temple"]["name"]
    if "type" not in data:
        return title, "pseudoperipteral tetrastyle, podium", _PORTUNUS_SOURCES
    t = data["type"]
    kind = (
        f"{t['arrangement'].replace('_', ' ')} {_WORDS.get(t['front'], str(t['front']))} "
        f"{t.get('intercolumniation', 'eustyle')}"
    )
    return title, kind, tuple(data["temple"].get("sources", ()))
