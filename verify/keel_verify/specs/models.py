"""The models and mutants of ``spec/manifest.json``, and the .cfg edits they need.

A *model* is a TLA+ module and a .cfg file that TLC must check without error; the
manifest records its distinct-state count. A *mutant* is a module in ``spec/mutants/``
that extends a model's module with a deliberately broken action; it is checked with
its base model's constants, against the one property it must break, and TLC must
reject it with the expected exit code and property name. A *witness* is an invariant
of a model's own module that says "this never happens" about a state the model's
properties need to reach (an exclusion, a deaf period): TLC must find it violated, or the
property it guards is vacuous. It is checked like a mutant of the unchanged spec.

A model whose state space does not fit an exhaustive run may be checked in TLC's
simulation mode instead (the manifest's ``"simulate": {"depth": D, "traces": N}``, and
optionally ``"seed"``): N random behaviours of at most D states each, from a fixed seed and
one worker, so that a run is reproducible and the manifest records the states it checked
(``states_checked``) as it records an exhaustive model's distinct states. A simulation
checks the behaviours it draws, not every behaviour: a pass says no violation was found
in them. A mutant or witness may be looked for the same way (a violation TLC finds in a
random behaviour is a violation all the same).
"""

from __future__ import annotations

import json
import re
from dataclasses import dataclass, field
from pathlib import Path

# Section keywords of a TLC .cfg file.
CFG_KEYWORDS = frozenset(
    {
        "CONSTANT", "CONSTANTS", "INIT", "NEXT", "SPECIFICATION", "INVARIANT", "INVARIANTS",
        "PROPERTY", "PROPERTIES", "SYMMETRY", "CONSTRAINT", "CONSTRAINTS",
        "ACTION_CONSTRAINT", "ACTION_CONSTRAINTS", "CHECK_DEADLOCK", "VIEW", "ALIAS",
        "POSTCONDITION",
    }
)


# The seed of a simulation whose manifest entry names none.
DEFAULT_SEED = 1


@dataclass(frozen=True)
class Simulation:
    """TLC's simulation mode for a model: ``traces`` behaviours of at most ``depth`` states,
    drawn from ``seed`` (``-simulate num=traces -depth depth -seed seed``)."""

    depth: int
    traces: int
    seed: int = DEFAULT_SEED

    def tlc_args(self) -> list[str]:
        return ["-simulate", f"num={self.traces}", "-depth", str(self.depth),
                "-seed", str(self.seed)]

    def as_json(self) -> dict[str, int]:
        return {"depth": self.depth, "traces": self.traces, "seed": self.seed}


class ManifestError(Exception):
    """The manifest or a file it names is missing or malformed (exit 2)."""


@dataclass
class Model:
    name: str
    spec: str
    module: str
    cfg_text: str
    properties: list[str]
    distinct_states: int | None
    extra_files: dict[str, str] = field(default_factory=dict)
    config: str = ""  # the .cfg file in spec/ (empty for a model built from a mission)
    # A larger model: `keel-verify specs --all` and `./keel bench specs` check it, CI does not
    # (the manifest's "bench": true; every spec keeps a model in CI).
    bench: bool = False
    # Checked in TLC's simulation mode (the manifest's "simulate"), not exhaustively; the
    # manifest then records the states it checked, not distinct states.
    simulate: Simulation | None = None
    states_checked: int | None = None

    @property
    def recorded_count(self) -> int | None:
        """The count the manifest records: states checked by a simulation, else distinct
        states."""
        return self.states_checked if self.simulate is not None else self.distinct_states


@dataclass
class Mutant:
    name: str
    base: str
    module: str
    specification: str
    property: str
    exit_code: int
    description: str = ""
    constants: dict[str, str] = field(default_factory=dict)  # overrides of the base cfg
    kind: str = "mutant"  # "mutant" | "witness"
    # Left out of CI, as a "bench" model is (a mutant or witness of a bench model that takes
    # minutes to reach): `keel-verify specs --all` and `./keel bench specs` check it.
    bench: bool = False
    # Looked for in TLC's simulation mode (the manifest's "simulate"): a violation in a
    # random behaviour rejects it as one found exhaustively does.
    simulate: Simulation | None = None


@dataclass
class Manifest:
    path: Path
    models: list[Model]
    mutants: list[Mutant]
    raw: dict[str, object]

    def model(self, name: str) -> Model:
        for model in self.models:
            if model.name == name:
                return model
        raise ManifestError(f"no model named {name!r} in {self.path}")


def cfg_sections(cfg_text: str) -> list[tuple[str, list[str]]]:
    """The .cfg text as (keyword, lines) sections; comments are kept with their section."""
    sections: list[tuple[str, list[str]]] = [("", [])]
    for line in cfg_text.splitlines():
        code = line.split("\\*", 1)[0].strip()
        word = code.split()[0] if code else ""
        if word in CFG_KEYWORDS:
            sections.append((word, [line]))
        else:
            sections[-1][1].append(line)
    return sections


def cfg_names(cfg_text: str, keywords: set[str]) -> list[str]:
    """The names listed under the given section keywords."""
    names: list[str] = []
    for keyword, lines in cfg_sections(cfg_text):
        if keyword not in keywords:
            continue
        for index, line in enumerate(lines):
            words = line.split("\\*", 1)[0].split()
            names.extend(words[1:] if index == 0 else words)
    return names


def invariants_of(cfg_text: str) -> list[str]:
    return cfg_names(cfg_text, {"INVARIANT", "INVARIANTS"})


def override_constants(cfg_text: str, constants: dict[str, str]) -> str:
    """The .cfg with the named constants' values replaced (``Name = value`` lines)."""
    for name, value in constants.items():
        pattern = re.compile(rf"^(\s*){re.escape(name)}\s*=.*$", re.MULTILINE)
        if not pattern.search(cfg_text):
            raise ManifestError(f"constant {name} is not set in the base model's .cfg")
        replacement = f"{name} = {value}"
        cfg_text = pattern.sub(lambda m, text=replacement: m.group(1) + text, cfg_text)
    return cfg_text


def retarget_cfg(cfg_text: str, specification: str, prop: str,
                 constants: dict[str, str] | None = None, invariant: bool = False) -> str:
    """The base model's .cfg checking ``specification`` against ``prop`` alone.

    ``prop`` is an invariant when the base lists it as one, or when ``invariant`` says so
    (a witness, which the base model does not check)."""
    cfg_text = override_constants(cfg_text, constants or {})
    is_invariant = invariant or prop in invariants_of(cfg_text)
    kept = [
        "\n".join(lines)
        for keyword, lines in cfg_sections(cfg_text)
        if keyword not in {"SPECIFICATION", "INIT", "NEXT", "INVARIANT", "INVARIANTS",
                           "PROPERTY", "PROPERTIES"}
    ]
    kept.append(f"SPECIFICATION {specification}")
    kept.append(f"{'INVARIANT' if is_invariant else 'PROPERTY'} {prop}")
    return "\n".join(part for part in kept if part.strip()) + "\n"


# The first TLCGet/TLCSet register a probe uses (witness i has PROBE_REGISTER + i); the
# specs use none.
PROBE_REGISTER = 9000
PROBE_MARKER = "keel-witness-reached"


def specification_of(cfg_text: str) -> str | None:
    """The SPECIFICATION a .cfg checks (None: it has none, or INIT/NEXT)."""
    names = cfg_names(cfg_text, {"SPECIFICATION"})
    return names[0] if len(names) == 1 else None


def fair_version_of(spec_dir: Path, name: str) -> str | None:
    """The specification ``name`` adds fairness to: ``W`` when every definition of ``name``
    in the spec folder is one line, ``name == W /\\ F1 /\\ ...``, each ``Fi`` a fairness
    condition (``WF_``/``SF_``, or a definition whose name says ``Fairness``): the same
    initial states and steps, so the same reachable states. Else None."""
    pattern = re.compile(rf"^{re.escape(name)}\s*==\s*(\w+)\s*/\\(.*)$", re.MULTILINE)
    defined = re.compile(rf"^{re.escape(name)}\s*==", re.MULTILINE)
    found: set[str] = set()
    for path in spec_dir.glob("*.tla"):
        text = path.read_text()
        definitions = len(defined.findall(text))
        unfolded = pattern.findall(text)
        if definitions != len(unfolded):
            return None
        for base, rest in unfolded:
            conjuncts = [part.strip() for part in rest.split("/\\")]
            if not all(re.search(r"\b(WF_|SF_)|Fairness", part) for part in conjuncts):
                return None
            found.add(base)
    return found.pop() if len(found) == 1 else None


def can_probe(model: Model, witness: Mutant, spec_dir: Path) -> bool:
    """Whether ``witness`` can be looked for in ``model``'s own run (probe_model): the same
    reachable states (its specification, or the model's is the witness's with fairness added)
    and the same simulation or none."""
    if witness.kind != "witness" or witness.base != model.name or witness.simulate != model.simulate:
        return False
    checked = specification_of(model.cfg_text)
    if checked is None:
        return False
    return witness.specification in (checked, fair_version_of(spec_dir, checked))


def probe_model(model: Model, witnesses: list[Mutant]) -> tuple[str, str, dict[str, str]]:
    """``model``'s run with ``witnesses`` looked for in it: (module, cfg text, extra files).

    A wrapper module extends the model's and adds one invariant, always true, that prints
    ``<<"keel-witness-reached", "NAME">>`` the first time (in each TLC worker) it sees a
    state violating a witness's invariant; a register per witness (TLCSet/TLCGet, set in
    an ASSUME before any worker starts) keeps it from printing again. The model's states,
    properties and counts are unchanged; every witness the run reaches is named in its
    output (probe_results)."""
    module = f"KeelProbe{model.module}"
    registers = [(PROBE_REGISTER + index, witness) for index, witness in enumerate(witnesses, 1)]
    assume = " /\\ ".join(f"TLCSet({register}, FALSE)" for register, _ in registers)
    probes = "\n".join(
        f"    /\\ ((~{witness.property} /\\ ~TLCGet({register})) =>\n"
        f"          (PrintT(<<\"{PROBE_MARKER}\", \"{witness.name}\">>) /\\ TLCSet({register}, TRUE)))"
        for register, witness in registers)
    text = (f"---- MODULE {module} ----\n"
            f"\\* Generated by keel-verify specs: {model.name}'s run, with its witnesses looked for.\n"
            f"EXTENDS {model.module}, TLC\n"
            f"ASSUME {assume}\n"
            f"KeelWitnessProbe ==\n{probes}\n"
            "====\n")
    cfg = model.cfg_text.rstrip("\n") + "\nINVARIANT KeelWitnessProbe\n"
    return module, cfg, {**model.extra_files, f"{module}.tla": text}


def probe_results(output: str) -> set[str]:
    """The witnesses a probed run's output says it reached."""
    return set(re.findall(rf'<<"{PROBE_MARKER}", "([A-Za-z0-9_]+)">>', output))


def mutant_description(spec_dir: Path, module: str) -> str:
    """The first sentence of a mutant module's header comment."""
    path = spec_dir / "mutants" / f"{module}.tla"
    if not path.is_file():
        return ""
    text = []
    for line in path.read_text().splitlines():
        line = line.strip()
        if line.startswith("(*") and line.endswith("*)") and not line.startswith("(**"):
            text.append(line[2:-2].strip())
        elif text:
            break
    joined = " ".join(text)
    return joined.split(". ")[0].rstrip(".") + "." if joined else ""


def simulation_of(entry: dict[str, object], where: str) -> Simulation | None:
    """A model entry's "simulate" (None when it has none)."""
    raw = entry.get("simulate")
    if raw is None:
        return None
    if not isinstance(raw, dict) or set(raw) - {"depth", "traces", "seed"}:
        raise ManifestError(f"{where}: \"simulate\" takes depth, traces and seed")
    try:
        simulation = Simulation(depth=int(raw["depth"]), traces=int(raw["traces"]),
                                seed=int(raw.get("seed", DEFAULT_SEED)))
    except (KeyError, TypeError, ValueError) as error:
        raise ManifestError(f"{where}: \"simulate\" needs depth and traces ({error})") from error
    if simulation.depth < 1 or simulation.traces < 1:
        raise ManifestError(f"{where}: \"simulate\" needs a positive depth and traces")
    return simulation


def load_manifest(spec_dir: Path) -> Manifest:
    path = spec_dir / "manifest.json"
    try:
        raw = json.loads(path.read_text())
    except (OSError, json.JSONDecodeError) as error:
        raise ManifestError(f"{path}: {error}") from error
    models = []
    try:
        for entry in raw["models"]:
            cfg_path = spec_dir / entry["config"]
            if not (spec_dir / f"{entry['module']}.tla").is_file():
                raise ManifestError(f"{path}: module {entry['module']}.tla not found")
            try:
                cfg_text = cfg_path.read_text()
            except OSError as error:
                raise ManifestError(f"{path}: {error}") from error
            models.append(
                Model(
                    name=entry["name"],
                    spec=entry["spec"],
                    module=entry["module"],
                    cfg_text=cfg_text,
                    properties=list(entry.get("properties", [])),
                    distinct_states=entry.get("distinct_states"),
                    config=entry["config"],
                    bench=bool(entry.get("bench", False)),
                    simulate=simulation_of(entry, f"{path}: model {entry['name']}"),
                    states_checked=entry.get("states_checked"),
                )
            )
        names = {model.name for model in models}
        mutants = []
        for entry in raw["mutants"]:
            if entry["base"] not in names:
                raise ManifestError(f"{path}: mutant {entry['name']}: unknown base model")
            if not (spec_dir / "mutants" / f"{entry['module']}.tla").is_file():
                raise ManifestError(f"{path}: mutants/{entry['module']}.tla not found")
            mutants.append(
                Mutant(
                    name=entry["name"],
                    base=entry["base"],
                    module=entry["module"],
                    specification=entry["specification"],
                    property=entry["property"],
                    exit_code=int(entry["exit_code"]),
                    description=mutant_description(spec_dir, entry["module"]),
                    constants={k: str(v) for k, v in entry.get("constants", {}).items()},
                    bench=bool(entry.get("bench", False)),
                    simulate=simulation_of(entry, f"{path}: mutant {entry['name']}"),
                )
            )
        by_name = {model.name: model for model in models}
        for entry in raw.get("witnesses", []):
            if entry["base"] not in by_name:
                raise ManifestError(f"{path}: witness {entry['name']}: unknown base model")
            base = by_name[entry["base"]]
            mutants.append(
                Mutant(
                    name=entry["name"],
                    base=entry["base"],
                    module=base.module,
                    specification=entry.get("specification", "Spec"),
                    property=entry["property"],
                    exit_code=12,
                    description=str(entry.get("description", "")),
                    kind="witness",
                    bench=bool(entry.get("bench", False)),
                    simulate=simulation_of(entry, f"{path}: witness {entry['name']}"),
                )
            )
    except (KeyError, TypeError, ValueError) as error:
        raise ManifestError(f"{path}: malformed entry ({error})") from error
    return Manifest(path=path, models=models, mutants=mutants, raw=raw)


def update_counts(manifest: Manifest, counts: dict[str, int]) -> None:
    """Write new counts for the named models into the manifest file: distinct states, or
    the states a simulation checked."""
    for entry in manifest.raw["models"]:  # type: ignore[union-attr]
        if entry["name"] in counts:
            key = "states_checked" if "simulate" in entry else "distinct_states"
            entry[key] = counts[entry["name"]]
    manifest.path.write_text(json.dumps(manifest.raw, indent=2) + "\n")
