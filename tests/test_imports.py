"""Every module of the package imports, in the quick tier too: a module whose tests are all marked slow still
fails fast on a broken import."""

from __future__ import annotations

import importlib
import pkgutil

import curiosity_cli

#: Modules that do something when imported: ``python -m curiosity_cli`` runs the command line.
RUN_ON_IMPORT = {"curiosity_cli.__main__"}


def test_every_module_imports():
    found = pkgutil.walk_packages(curiosity_cli.__path__, "curiosity_cli.")
    modules = [m.name for m in found if m.name not in RUN_ON_IMPORT]
    assert {"curiosity_cli.cli", "curiosity_cli.drive.driver", "curiosity_cli.topics._sampler"} <= set(modules)
    failed = {}
    for module in modules:
        try:
            importlib.import_module(module)
        except Exception as exc:  # noqa: BLE001 - every module that fails, named at once
            failed[module] = f"{type(exc).__name__}: {exc}"
    assert not failed, failed
