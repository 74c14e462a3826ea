"""``curiosity vocab``: learn the visual vocabularies shipped in data/vocab/."""

from __future__ import annotations

from pathlib import Path

import typer

from curiosity_cli.cli.app import app, usage_errors
from curiosity_cli.api.maps import MAX_VOCABULARY

vocab_app = typer.Typer(help="Learn visual vocabularies from photographs unrelated to the maps.", no_args_is_help=True)
app.add_typer(vocab_app, name="vocab")


@vocab_app.command("build")
@usage_errors
def build(
    out: Path = typer.Option(Path("data/vocab"), "--out", help="Folder to write orb-N.npz and texton-N.npz to."),
    orb_words: int = typer.Option(
        5000, "--orb-words", min=2, max=MAX_VOCABULARY, help="ORB vocabulary size (the paper's 5000)."
    ),
    texton_words: int = typer.Option(
        1000, "--texton-words", min=2, max=MAX_VOCABULARY, help="Texton vocabulary size (the paper's 1000)."
    ),
    seed: int = typer.Option(0, "--seed", min=0, help="Seed of the clustering."),
) -> None:
    """Cluster ORB descriptors (k-majority) and MR8 responses (k-means) of scikit-image's photographs.

    A vocabulary already in --out that was built by the same recipe (size, seed, versions) is kept: run the same command again to finish a stopped build, and delete a file to build it again.
    """
    from curiosity_cli import api

    api.build_vocabularies(out, orb_words=orb_words, texton_words=texton_words, seed=seed, log=typer.echo)
