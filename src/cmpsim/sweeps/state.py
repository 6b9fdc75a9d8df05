"""The state directory of a sweep: ``PATH.parts/`` with a manifest and one JSON per finished point."""

from __future__ import annotations

import json
import shutil
from pathlib import Path

from .._version import __version__
from .spec import SweepSpec


class _State:
    """``PATH.parts/``: manifest.json plus one JSON per finished point, each written atomically."""

    def __init__(self, out: Path):
        self.dir = Path(str(out) + ".parts")
        self.manifest = self.dir / "manifest.json"

    def part_files(self) -> list[Path]:
        if not self.dir.is_dir():
            return []
        return [p for p in self.dir.glob("*.json") if p.name != "manifest.json" and not p.name.startswith(".")]

    def exists(self) -> bool:
        return self.manifest.exists() or bool(self.part_files())

    def clean_temporaries(self) -> None:
        if self.dir.is_dir():
            for p in self.dir.glob(".*"):
                if p.is_file():
                    p.unlink(missing_ok=True)

    def read_manifest(self) -> dict | None:
        try:
            return json.loads(self.manifest.read_text(encoding="utf-8"))
        except (OSError, ValueError):
            return None

    def begin(self, identity: str, spec: SweepSpec, n: int, options: dict) -> None:
        from ..io import atomic_write_text

        self.dir.mkdir(parents=True, exist_ok=True)
        text = json.dumps(
            {"identity": identity, "cmpsim_version": __version__, "points": n, "options": options, "sweep_toml": spec.source},
            indent=1,
        )
        atomic_write_text(self.manifest, text + "\n")

    def load(self, keys: set[str]) -> dict[str, dict]:
        done = {}
        for p in self.part_files():
            try:
                rec = json.loads(p.read_text(encoding="utf-8"))
            except (OSError, ValueError):
                continue  # cannot happen with atomic writes; recomputed if it does
            if isinstance(rec, dict) and rec.get("key") in keys and p.stem == rec["key"]:
                done[rec["key"]] = rec
        return done

    def save(self, rec: dict) -> None:
        from ..io import atomic_write_text

        atomic_write_text(self.dir / f"{rec['key']}.json", json.dumps(rec))

    def remove(self) -> None:
        shutil.rmtree(self.dir, ignore_errors=True)
