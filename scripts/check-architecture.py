#!/usr/bin/env python3
"""The claims of ARCHITECTURE.md that a script can check; CI runs it (`.ci/run`). Exits 1, naming each violation.

1. Layering: every normal dependency between workspace crates points down the layers below (a crate may depend on
   crates of a lower layer, or of its own layer's folder); `metaplate-ground-truth` and `metaplate-fixtures` are test
   fixtures, so only dev-dependencies name them.
2. No import circle within a crate: of two sibling modules (children of one parent module), when one uses the other
   the other does not use it back, directly or around a longer circle. A module's own submodules and its ancestors are
   not counted (a child using its parent's items is how Rust modules nest), nor is what a crate's `error` module
   names (its variants carry the other modules' types, and every module returns it: a sink, not a layer). Test
   modules (`#[cfg(test)]` and what follows it in a file) are left out.
3. File size: no Rust source file of a crate's `src/` is longer than MAX_LINES (a file that long holds more than one
   concept: split it), and the binary's `src/` (crates/cli) holds at most MAX_BINARY_LINES in all (a thin binary:
   each command parses, calls a library, prints).
4. No test left unrun: a library or binary built without a test harness (`[lib] test = false`, which saves the test
   build a second compilation of it) holds no `#[cfg(test)]` code, whose tests nothing would run.

usage: python3 scripts/check-architecture.py   (from anywhere in the repository)
"""

import json
import re
import subprocess
import sys
from collections import defaultdict
from pathlib import Path

MAX_LINES = 800
MAX_BINARY_LINES = 3000

# From the bottom up: a crate's folder (relative to the workspace root) decides its layer.
LAYERS = [
    ("crates/foundation/", 0),
    ("protocols/", 1),
    ("drivers/", 2),
    ("crates/simulator/", 3),
    ("mock-hardware/", 4),
    ("crates/wavefield/", 5),
    ("recipes", 6),
    ("crates/interchange", 7),
    ("crates/experiments", 8),
    ("crates/evaluation", 9),
    ("crates/monitor", 10),
    ("crates/cli", 11),
    ("crates/testing/", 12),
]
FIXTURES = {"metaplate-ground-truth", "metaplate-fixtures"}


def layer_of(rel: str) -> tuple[int, str]:
    for prefix, layer in LAYERS:
        if rel == prefix.rstrip("/") or rel.startswith(prefix):
            return layer, prefix
    sys.exit(f"check-architecture: {rel} is in no layer: add its folder to LAYERS (and to ARCHITECTURE.md)")


def check_layers(root: Path, meta: dict) -> list[str]:
    problems = []
    members = {p["name"]: p for p in meta["packages"] if p["id"] in meta["workspace_members"]}
    for name, package in sorted(members.items()):
        rel = str(Path(package["manifest_path"]).parent.relative_to(root))
        layer, folder = layer_of(rel)
        for dep in package["dependencies"]:
            if dep["name"] not in members or dep.get("kind") == "dev":
                continue
            dep_rel = str(Path(members[dep["name"]]["manifest_path"]).parent.relative_to(root))
            dep_layer, dep_folder = layer_of(dep_rel)
            if dep["name"] in FIXTURES:
                problems.append(f"layering: {name} depends on the test fixture {dep['name']} (dev-dependencies only)")
            elif dep_layer > layer or (dep_layer == layer and dep_folder != folder):
                problems.append(f"layering: {name} ({rel}) depends on {dep['name']} ({dep_rel}), a layer up or aside")
    return problems


USE_RE = re.compile(r"\b(crate|super|self)((?:::[A-Za-z_][A-Za-z0-9_]*)+)")
GROUP_RE = re.compile(r"\buse\s+(crate|super|self)((?:::[A-Za-z_][A-Za-z0-9_]*)*)::\{([^;]*)\}", re.S)


def module_path(src: Path, file: Path) -> tuple[str, ...]:
    parts = list(file.relative_to(src).with_suffix("").parts)
    if parts[-1] in ("lib", "main", "mod"):
        parts = parts[:-1]
    return tuple(parts)


def resolve(base: tuple[str, ...], head: str, tail: list[str]) -> tuple[str, ...] | None:
    if head == "crate":
        start = ()
    elif head == "self":
        start = base
    else:
        start = base
        while tail and tail[0] == "super":
            tail = tail[1:]
            start = start[:-1]
        start = start[:-1] if start else None
        if start is None:
            return None
    return start + tuple(tail)


def check_circles(src: Path, crate: str) -> list[str]:
    files = sorted(src.rglob("*.rs"))
    modules = {module_path(src, f) for f in files}
    edges = defaultdict(set)
    for file in files:
        base = module_path(src, file)
        if base[-1:] == ("error",):
            continue
        text = file.read_text()
        cut = text.find("#[cfg(test)]")
        if cut >= 0:
            text = text[:cut]
        text = re.sub(r"//[^\n]*", "", text)
        refs = []
        for head, path, group in GROUP_RE.findall(text):
            prefix = [p for p in path.split("::") if p]
            for item in re.split(r"[,\s]+", re.sub(r"\{[^}]*\}", "", group)):
                item = item.split("::")[0].strip()
                if item and item not in ("self", "*"):
                    refs.append((head, prefix + [item]))
            refs.append((head, prefix))
        for head, path in USE_RE.findall(text):
            refs.append((head, [p for p in path.split("::") if p]))
        for head, tail in refs:
            target = resolve(base, head, list(tail))
            if target is None:
                continue
            # The longest known module the path names.
            while target and target not in modules:
                target = target[:-1]
            if not target or target[: len(base)] == base or base[: len(target)] == target:
                continue
            common = 0
            while common < min(len(base), len(target)) and base[common] == target[common]:
                common += 1
            edges[base[: common + 1]].add(target[: common + 1])
    problems = []
    # Circles among siblings: strongly connected components of more than one module.
    index, low, stack, on, counter, found = {}, {}, [], set(), [0], []

    def visit(v):
        index[v] = low[v] = counter[0]
        counter[0] += 1
        stack.append(v)
        on.add(v)
        for w in edges.get(v, ()):
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            component = []
            while True:
                w = stack.pop()
                on.discard(w)
                component.append(w)
                if w == v:
                    break
            if len(component) > 1:
                found.append(sorted("::".join(c) for c in component))

    sys.setrecursionlimit(10000)
    for v in list(edges):
        if v not in index:
            visit(v)
    for component in found:
        problems.append(f"import circle in {crate}: " + " <-> ".join(component))
    return problems


def check_sizes(root: Path, src: Path) -> list[str]:
    problems = []
    for file in sorted(src.rglob("*.rs")):
        lines = sum(1 for _ in file.open())
        if lines > MAX_LINES:
            problems.append(f"file size: {file.relative_to(root)} has {lines} lines (limit {MAX_LINES}): split it")
    return problems


def check_harness(root: Path, package: dict) -> list[str]:
    problems = []
    for target in package["targets"]:
        if target.get("test", True) or not {"lib", "bin"} & set(target["kind"]):
            continue
        # Every file of the crate's src/ (a bin's modules sit beside its main.rs).
        for file in sorted(Path(target["src_path"]).parent.rglob("*.rs")):
            if "#[cfg(test)]" in file.read_text():
                problems.append(
                    f"unrun tests: {file.relative_to(root)} has #[cfg(test)] code, but {package['name']}'s "
                    f"{target['kind'][0]} target is built without a test harness (test = false): move its tests to "
                    "the crate's tests/"
                )
    return problems


def main() -> int:
    root = Path(subprocess.check_output(["git", "rev-parse", "--show-toplevel"], text=True).strip())
    meta = json.loads(
        subprocess.check_output(["cargo", "metadata", "--format-version", "1", "--no-deps", "--locked"], cwd=root)
    )
    problems = check_layers(root, meta)
    for package in meta["packages"]:
        if package["id"] not in meta["workspace_members"]:
            continue
        src = Path(package["manifest_path"]).parent / "src"
        if src.is_dir():
            problems += check_circles(src, package["name"])
            problems += check_sizes(root, src)
        problems += check_harness(root, package)
    binary_lines = sum(sum(1 for _ in f.open()) for f in (root / "crates/cli/src").rglob("*.rs"))
    if binary_lines > MAX_BINARY_LINES:
        problems.append(
            f"thin binary: crates/cli/src has {binary_lines} lines (limit {MAX_BINARY_LINES}): move logic to a library"
        )
    for problem in problems:
        print(f"check-architecture: {problem}", file=sys.stderr)
    count = len(meta["workspace_members"])
    print(f"check-architecture: {count} crates, {len(problems)} problem(s)")
    return 1 if problems else 0


if __name__ == "__main__":
    sys.exit(main())
