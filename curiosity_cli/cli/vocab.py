"""``curiosity vocab``: learn the visual vocabularies shipped in data/vocab/."""

from __future__ import annotations

from pathlib import Path

import typer

from curiosity_cli.cli import app

vocab_app = typer.Typer(help="Learn visual vocabularies from photographs unrelated to the maps.", no_args_is_help=True)
app.add_typer(vocab_app, name="vocab")


@vocab_app.command("build")
def build(
    out: Path = typer.Option(Path("data/vocab"), "--out", help="Folder to write orb-N.npz and texton-N.npz to."),
    orb_words: int = typer.Option(5000, "--orb-words", help="ORB vocabulary size (the paper's 5000)."),
    texton_words: int = typer.Option(1000, "--texton-words", help="Texton vocabulary size (the paper's 1000)."),
    seed: int = typer.Option(0, "--seed", help="Seed of the clustering."),
) -> None:
    """Cluster ORB descriptors (k-majority) and MR8 responses (k-means) of scikit-image's photographs."""
    from curiosity_cli.errors import CuriosityError
    from curiosity_cli.files import display_path
    from curiosity_cli.words.vocab import build_orb_vocabulary, build_texton_vocabulary, save_vocabulary

    for option, value in (("--orb-words", orb_words), ("--texton-words", texton_words)):
        if value < 2:
            raise CuriosityError(f"{option}: got {value}, expected an integer >= 2")
    for builder, size in ((build_texton_vocabulary, texton_words), (build_orb_vocabulary, orb_words)):
        vocabulary = builder(size, seed=seed, log=typer.echo)
        path = save_vocabulary(vocabulary, out)
        typer.echo(f"wrote {display_path(path)} (sha256 {vocabulary.sha256[:16]}…)")
