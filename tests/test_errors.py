"""Library errors name the library's arguments; the command line names its options."""

import pickle

import pytest

from curiosity_cli.errors import RERUN, ConfigError, CuriosityError, ParameterError


def test_the_library_words_name_the_argument_and_the_stage_with_force():
    error = CuriosityError(f"out: got 'a.gif'; or run {RERUN} to redo it", parameter="out", rerun="explore")
    assert str(error) == "out: got 'a.gif'; or run explore with force=True to redo it"


def test_the_command_line_words_replace_the_argument_by_its_option_and_name_the_command():
    error = CuriosityError(f"video_out a.gif: expected .mp4; or run {RERUN} to redo it", parameter="video_out",
                           rerun="explore")
    rendered = error.render(option="--video-out", rerun="`curiosity explore --force`")
    assert rendered == "--video-out a.gif: expected .mp4; or run `curiosity explore --force` to redo it"


def test_a_message_must_begin_with_its_parameter():
    with pytest.raises(ValueError, match="must begin with 'out'"):
        CuriosityError("got 'a.gif'", parameter="out")


@pytest.mark.parametrize("kind", [CuriosityError, ConfigError, ParameterError])
def test_the_argument_and_stage_survive_a_trip_to_a_worker_process(kind):
    error = pickle.loads(pickle.dumps(kind(f"noise 'x': bad; run {RERUN}", parameter="noise", rerun="extract")))
    assert type(error) is kind
    assert (error.parameter, error.rerun) == ("noise", "extract")
    assert error.render(option="--noise", rerun="R") == "--noise 'x': bad; run R"
