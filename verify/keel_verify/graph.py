"""``keel-verify graph MISSION.yaml -o graph.svg``: draw the decision graph (Graphviz).

One cluster per phase; a box per configuration (master, observers, placements), a SAFE
octagon per phase, failure edges labelled with the failed node, planned phase changes
dashed. The mission is checked first and what the check found is drawn in red: the
configurations that break a rule, the edges that lead to a violation, and the missing
edges (to a red "?"). ``-o x.dot`` writes the Graphviz source; any other extension is
rendered by ``dot -T<extension>``.
"""

from __future__ import annotations

import argparse
import shutil
import subprocess
import sys
from collections import defaultdict
from pathlib import Path

from keel_verify.check.core import InputError, check_file
from keel_verify.check.result import CheckResult
from keel_verify.mission import SAFE, Mission

RED = "#c62828"


def _quote(text: str) -> str:
    """A Graphviz string; ``\\l`` line ends in labels are kept (names never hold a
    backslash: the schema's name pattern forbids it)."""
    return '"' + text.replace('"', '\\"') + '"'


def to_dot(mission: Mission, result: CheckResult) -> str:
    bad_configs: dict[str, list[str]] = defaultdict(list)
    bad_edges: dict[tuple[str, str], list[str]] = defaultdict(list)  # (config, node|phase)
    missing: dict[tuple[str, str], str] = {}
    for v in result.violations:
        if v.kind == "missing-transition" and v.node:
            missing[(v.config, v.node)] = v.message
        elif v.kind in ("master-mismatch", "safe-mode-within-tolerance") and v.node:
            bad_edges[(v.config, v.node)].append(v.kind)
        elif v.kind == "phase-transition-invalid":
            bad_edges[(v.config, "phase:" + v.target)].append(v.kind)
            if v.steps and v.steps[-1].to == "?":
                missing[(v.config, "phase " + v.target)] = v.message
        elif v.config and v.kind != "safe-mode-unhostable":
            bad_configs[v.config].append(v.kind)
        elif v.kind == "safe-mode-unhostable" and v.config:
            bad_configs[v.config].append(f"{v.kind} ({v.node})")
    verdict = "PROVED valid" if result.valid else f"{len(result.roots())} violations"
    out = [
        f"digraph {_quote(mission.name)} {{",
        "  rankdir=LR; compound=true;",
        '  node [shape=box, fontname="Helvetica", fontsize=10];',
        '  edge [fontname="Helvetica", fontsize=9];',
        f"  label={_quote(f'{mission.name}: {verdict}')};",
    ]
    for p_index, phase in enumerate(mission.phases.values()):
        out.append(f"  subgraph cluster_{p_index} {{")
        out.append(f"    label={_quote('phase ' + phase.name)};")
        for name, c in phase.configurations.items():
            tasks = "\\l".join(f"{t} @ {n}" for t, n in c.placement.items())
            label = (f"{name}{' (initial)' if name == phase.initial else ''}\\l"
                     f"master {c.master}; observers {', '.join(c.observers) or '-'}\\l{tasks}\\l")
            attrs = f"label={_quote(label)}"
            if name in bad_configs:
                kinds = ", ".join(sorted(set(bad_configs[name])))
                attrs += f', color="{RED}", penwidth=2, fontcolor="{RED}", xlabel={_quote(kinds)}'
            out.append(f"    {_quote(name)} [{attrs}];")
        safe = f"SAFE@{phase.name}"
        out.append(f'    {_quote(safe)} [label="SAFE", shape=octagon];')
        for config, edges in phase.on_failure.items():
            for node, target in edges.items():
                dest = safe if target == SAFE else target
                attrs = f"label={_quote(node)}"
                if (config, node) in bad_edges:
                    attrs += f', color="{RED}", fontcolor="{RED}", penwidth=2'
                out.append(f"    {_quote(config)} -> {_quote(dest)} [{attrs}];")
        out.append("  }")
        for target_phase, mapping in phase.on_phase.items():
            for config, target in mapping.items():
                attrs = f"style=dashed, label={_quote('phase ' + target_phase)}"
                if (config, "phase:" + target_phase) in bad_edges:
                    attrs += f', color="{RED}", fontcolor="{RED}", penwidth=2'
                out.append(f"  {_quote(config)} -> {_quote(target)} [{attrs}];")
    for n, ((config, node), message) in enumerate(sorted(missing.items())):
        hole = f"missing{n}"
        out.append(f'  {hole} [label="?", shape=circle, color="{RED}", fontcolor="{RED}", '
                   f"tooltip={_quote(message)}];")
        out.append(f'  {_quote(config)} -> {hole} [label={_quote(node)}, color="{RED}", '
                   f'fontcolor="{RED}", style=bold];')
    out.append("}")
    return "\n".join(out) + "\n"


# The output formats, by the file's extension: Graphviz's source as it is, or rendered.
FORMATS = ("svg", "png", "pdf", "dot", "gv", "jpg", "jpeg", "gif", "ps", "eps", "svgz",
           "xdot", "json")


def register(subparsers: argparse._SubParsersAction) -> None:
    parser = subparsers.add_parser(
        "graph", help="draw a mission's decision graph with its violations (Graphviz)",
        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("mission", help="mission file (YAML, schema 1)")
    parser.add_argument("-o", "--output", required=True,
                        help="output file; the extension picks the format (svg, png, pdf, dot)")
    parser.add_argument("--max-failures", type=int, metavar="K", default=None,
                        help="check failure sequences of at most K failures")
    parser.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    output = Path(args.output)
    fmt = output.suffix.lstrip(".").lower() or "svg"
    if fmt not in FORMATS:  # a bad argument: said before anything is proved
        print(f"keel-verify: graph: {output}: no output format '{fmt}'; give a file ending "
              f"in {', '.join('.' + f for f in FORMATS)}", file=sys.stderr)
        return 2
    try:
        result, mission = check_file(args.mission, args.max_failures)
    except InputError as error:
        for e in error.errors:
            print(e, file=sys.stderr)
        return 2
    if mission is None:  # names or ports broken: nothing to draw from
        for v in result.violations:
            print(f"{v.file}:{v.line}:{max(1, v.col)}: {v.kind}: {v.message}", file=sys.stderr)
        return 1  # violations, as `check` reports them (docs/missions.md, "Exit codes")
    source = to_dot(mission, result)
    if fmt in ("dot", "gv"):
        output.write_text(source, encoding="utf-8")
    else:
        dot = shutil.which("dot")
        if dot is None:
            print("keel-verify: graph: Graphviz 'dot' is not installed (./keel setup installs "
                  "the Debian package graphviz); use -o FILE.dot for the source", file=sys.stderr)
            return 2
        done = subprocess.run([dot, f"-T{fmt}", "-o", str(output)], input=source, text=True,
                              capture_output=True, check=False)
        if done.returncode != 0:
            print(f"keel-verify: graph: dot failed: {done.stderr.strip()}", file=sys.stderr)
            return 2
    if result.valid:
        status = "proved valid"
    elif result.violations:
        more = len(result.violations) - len(result.roots())
        roots = len(result.roots())
        status = (f"{roots} violation{'' if roots == 1 else 's'} drawn in red"
                  + (f", {more} more follow from them" if more else ""))
    else:
        status = f"not proved: undecided ({result.reason})"
    print(f"{output}: decision graph of {mission.name} ({status})")
    # The exit code check gives (docs/missions.md, "Exit codes"): 3 when undecided.
    if result.valid:
        return 0
    return 1 if result.violations else 3
