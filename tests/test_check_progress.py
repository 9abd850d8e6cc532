"""The time-domain check reports its progress over the modes (a stiff model's mode takes tens of
seconds): the callback of ``check_modes`` and the CLI's bar on stderr, shown with
``--progress``, never with ``--no-progress``, and by default only on a terminal (as ``mbseig
sweep``).  Reference: the number of modes the case lists (the double pendulum's two swings, its
modes table); no timing is asserted.
"""

from conftest import CASES

from mbseig.check import check_modes
from mbseig.cli import main
from mbseig.studies import analyze


def test_check_modes_reports_each_mode_then_the_end():
    a = analyze(CASES / "double_pendulum.toml")
    calls = []
    res = check_modes(a.model, a.eq, a.linear, a.modes, periods=2.0,
                      progress=lambda *c: calls.append(c))
    n = len(res.modes)
    assert n == len(a.modes) == 2
    assert calls == [("modes", k, n) for k in range(n + 1)]


def test_check_cli_bar_only_when_asked_or_on_a_terminal(capsys):
    case = str(CASES / "double_pendulum.toml")
    main(["check", case, "--periods", "2", "--progress"])
    out, err = capsys.readouterr()
    assert "2/2" in err and "modes" in err and "check: passed" in out
    main(["check", case, "--periods", "2", "--no-progress"])
    assert "2/2" not in capsys.readouterr().err
    main(["check", case, "--periods", "2"])  # stderr is captured here: not a terminal
    assert "2/2" not in capsys.readouterr().err


def test_an_unfinished_bar_is_ended_before_what_follows():
    """An error or Ctrl-C in the middle of a check or sweep: ``close()`` ends the bar's line, so
    that the one-line message starts on its own line; a finished bar is left as it is."""
    import io

    from mbseig.studies.runners import progress_bar

    stream = io.StringIO()
    show = progress_bar(stream)
    show("modes", 1, 3)
    assert not stream.getvalue().endswith("\n")
    show.close()
    text = stream.getvalue()
    assert text.endswith("\n") and "1/3" in text.splitlines()[-1]
    show("lines", 2, 2)  # finished: closed at once
    done = stream.getvalue()
    show.close()
    assert stream.getvalue() == done
