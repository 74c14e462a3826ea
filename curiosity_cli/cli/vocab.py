"""``curiosity vocab``: learn the visual vocabularies shipped in data/vocab/."""

from __future__ import annotations

from pathlib import Path

import typer

from curiosity_cli.cli import app
from curiosity_cli.config import MAX_VOCABULARY

vocab_app = typer.Typer(help="Learn visual vocabularies from photographs unrelated to the maps.", no_args_is_help=True)
app.add_typer(vocab_app, name="vocab")


@vocab_app.command("build")
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
    """Cluster ORB descriptors (k-majority) and MR8 responses (k-means) of scikit-image's photographs."""
    from curiosity_cli.files import display_path
    from curiosity_cli.words.vocab import build_orb_vocabulary, build_texton_vocabulary, save_vocabulary

    for builder, size in ((build_texton_vocabulary, texton_words), (build_orb_vocabulary, orb_words)):
        vocabulary = builder(size, seed=seed, log=typer.echo)
        path = save_vocabulary(vocabulary, out)
        typer.echo(f"wrote {display_path(path)} (sha256 {vocabulary.sha256[:16]}…)")
