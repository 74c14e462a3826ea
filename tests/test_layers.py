"""Data flows one way: no module imports a later stage of the pipeline (read with ``ast``, nothing imported).

The stages in order are ``maps``, ``words``, ``topics``, ``experiment``, ``explore``,
``label``, ``evaluate``, ``plots``: a stage may import the bottom layer, ``config``,
itself and the stages before it. ``experiment`` (the experiment folder as a unit: its
layout, recipes, files and maps' facts) sits between ``topics`` and ``explore``: the
stages that read and write experiment folders ask it, and it asks ``words`` how a map's
word store is named. ``config`` (the experiment settings) sits between ``maps`` and
``words``: it checks the maps a config names against the map registry, and every stage
after reads its settings. ``drive`` may import ``maps``, ``words``, ``topics`` and
``experiment`` (provenance); no stage imports ``drive``. The bottom layer (the top-level
modules: errors, files, paths, schema, workers ...) imports no stage and not ``config``,
and nothing below the command line imports ``cli``. Imports inside functions and under
``TYPE_CHECKING`` count as much as those at the top of a module.
"""

from __future__ import annotations

import ast
from pathlib import Path

import curiosity_cli

PACKAGE = Path(curiosity_cli.__file__).parent
STAGES = ("maps", "words", "topics", "experiment", "explore", "label", "evaluate", "plots")

#: What each room of the package may import besides the bottom layer and itself.
ALLOWED = {stage: set(STAGES[:i]) | ({"config"} if i else set()) for i, stage in enumerate(STAGES)}
ALLOWED["config"] = {"maps"}
ALLOWED["drive"] = {"maps", "config", "words", "topics", "experiment"}

#: Modules that put several stages together, and why; they may import any stage.
ORCHESTRATORS = {
    "cli": "the command line: thin commands over every stage",
    "__main__": "`python -m curiosity_cli`: runs the command line",
    "study": "`curiosity reproduce`: one experiment end to end, a sweep or a study's specifications through it, "
    "their report and curve (evaluate's pooled statistics, plots' figures), and a study's results of record",
    "api": "curiosity from Python: the commands as functions, an experiment's results as frames",
}


def room(module: str) -> str:
    """The room of ``curiosity_cli.<room>[.…]``: a stage, ``drive``, ``cli``, or a bottom module's own name."""
    parts = module.split(".")
    return parts[1] if len(parts) > 1 else ""


def imported_modules(path: Path, module: str) -> list[tuple[str, int]]:
    """Every ``curiosity_cli`` module (or name in one) the file imports, with its line."""
    package = module.split(".") if path.name == "__init__.py" else module.split(".")[:-1]
    found = []
    for node in ast.walk(ast.parse(path.read_text(), str(path))):
        if isinstance(node, ast.Import):
            found += [(alias.name, node.lineno) for alias in node.names]
        elif isinstance(node, ast.ImportFrom):
            base = package[: len(package) - node.level + 1] if node.level else []
            source = ".".join(base + ([node.module] if node.module else []))
            # `from curiosity_cli import explore` imports the stage itself
            found += [(f"{source}.{alias.name}", node.lineno) for alias in node.names]
    return [(name, line) for name, line in found if name.split(".")[0] == "curiosity_cli"]


def modules(package: Path) -> list[tuple[Path, str]]:
    found = []
    for path in sorted(package.rglob("*.py")):
        parts = path.relative_to(package.parent).with_suffix("").parts
        found.append((path, ".".join(parts[:-1] if parts[-1] == "__init__" else parts)))
    return found


def violations(package: Path = PACKAGE) -> list[str]:
    """``path:line: imports name`` for each import of a room the importing module may not use."""
    found = []
    for path, module in modules(package):
        own = room(module)
        if own in ORCHESTRATORS:
            continue
        allowed = ALLOWED.get(own, set()) | {own}
        for name, line in imported_modules(path, module):
            target = room(name)
            if target in (*STAGES, "config", "drive", "study", "cli", "__main__") and target not in allowed:
                found.append(f"{path.relative_to(package.parent)}:{line}: imports {name}")
    return found


def test_no_module_imports_a_later_stage():
    assert violations() == []


def test_every_room_is_known_and_every_orchestrator_exists():
    rooms = {room(module) for _, module in modules(PACKAGE)}
    assert set(STAGES) | {"drive", "cli"} <= rooms
    for name in ORCHESTRATORS:
        assert (PACKAGE / name).is_dir() or (PACKAGE / f"{name}.py").is_file(), name


def test_the_check_sees_imports_inside_functions_relative_ones_and_the_bottom_layers(tmp_path):
    fake = tmp_path / "curiosity_cli"
    (fake / "topics").mkdir(parents=True)
    (fake / "__init__.py").write_text("")
    (fake / "config.py").write_text("def load():\n    from curiosity_cli.explore.weights import WEIGHT_FUNCTIONS\n")
    (fake / "files.py").write_text("import curiosity_cli.drive.link\nfrom curiosity_cli import errors\n")
    (fake / "topics" / "__init__.py").write_text("")
    (fake / "topics" / "model.py").write_text("from ..evaluate import tables\nfrom . import neighbours\nfrom ..words import store\n")
    (fake / "maps").mkdir()
    (fake / "maps" / "__init__.py").write_text("")
    (fake / "maps" / "datasets.py").write_text("from curiosity_cli import schema\nfrom curiosity_cli.config import load_config\n")
    (fake / "paths.py").write_text("from curiosity_cli.config import CONFIG_DIR\n")
    (fake / "workers.py").write_text("from curiosity_cli.maps import datasets\n")  # config may import maps; the bottom may not
    (fake / "config.py").write_text(
        "from curiosity_cli.maps.datasets import dataset_path\ndef load():\n    from curiosity_cli.explore.weights import WEIGHT_FUNCTIONS\n"
    )
    assert violations(fake) == [
        "curiosity_cli/config.py:3: imports curiosity_cli.explore.weights.WEIGHT_FUNCTIONS",
        "curiosity_cli/files.py:1: imports curiosity_cli.drive.link",
        "curiosity_cli/maps/datasets.py:2: imports curiosity_cli.config.load_config",
        "curiosity_cli/paths.py:1: imports curiosity_cli.config.CONFIG_DIR",
        "curiosity_cli/topics/model.py:1: imports curiosity_cli.evaluate.tables",
        "curiosity_cli/workers.py:1: imports curiosity_cli.maps.datasets",
    ]


def import_circles(package: Path = PACKAGE) -> list[list[str]]:
    """Groups of modules that import each other, directly or round a circle (imports inside
    functions and under ``TYPE_CHECKING`` included); each sorted."""
    found = modules(package)
    names = {module for _, module in found}
    graph = {}
    for path, module in found:
        targets = set()
        for name, _ in imported_modules(path, module):
            parts = name.split(".")
            # `from a.b import c` imports module a.b.c if there is one, else a name in a.b
            target = next((".".join(parts[:i]) for i in range(len(parts), 0, -1) if ".".join(parts[:i]) in names), None)
            if target is not None and target != module:
                targets.add(target)
        graph[module] = targets
    # Tarjan's strongly connected components, iteratively: a component of more than one module is a circle
    index, low, on_stack, stack, circles = {}, {}, set(), [], []
    for root in graph:
        if root in index:
            continue
        work = [(root, iter(sorted(graph[root])))]
        index[root] = low[root] = len(index)
        stack.append(root)
        on_stack.add(root)
        while work:
            module, targets = work[-1]
            target = next(targets, None)
            if target is not None:
                if target not in index:
                    index[target] = low[target] = len(index)
                    stack.append(target)
                    on_stack.add(target)
                    work.append((target, iter(sorted(graph[target]))))
                elif target in on_stack:
                    low[module] = min(low[module], index[target])
                continue
            work.pop()
            if work:
                low[work[-1][0]] = min(low[work[-1][0]], low[module])
            if low[module] == index[module]:
                component = []
                while True:
                    member = stack.pop()
                    on_stack.discard(member)
                    component.append(member)
                    if member == module:
                        break
                if len(component) > 1:
                    circles.append(sorted(component))
    return circles


def test_no_import_circles():
    assert import_circles() == []


def test_an_import_circle_is_found(tmp_path):
    fake = tmp_path / "curiosity_cli"
    (fake / "study").mkdir(parents=True)
    (fake / "__init__.py").write_text("")
    (fake / "study" / "__init__.py").write_text("")
    (fake / "study" / "a.py").write_text("def f():\n    from curiosity_cli.study.b import g\n")
    (fake / "study" / "b.py").write_text("from curiosity_cli.study import a\n")
    (fake / "study" / "c.py").write_text("from curiosity_cli.study.a import f\n")
    assert import_circles(fake) == [["curiosity_cli.study.a", "curiosity_cli.study.b"]]
