"""The progress bar (`lumos.progress`): shown only for renders that last, with a line of figures beside it."""

import io

from lumos import progress


def test_the_bar_shows_its_note_and_a_callable_gets_the_fractions(monkeypatch):
    import rich.console

    out = io.StringIO()
    real = rich.console.Console
    monkeypatch.setattr(progress, "SHOW_AFTER_S", 0.0)
    monkeypatch.setattr(rich.console, "Console", lambda file: real(file=out, force_terminal=True, width=120))
    with progress.make_progress(True) as report:
        report.note("3/16 pieces, 1.25 M samples/s")
        report(0.25)
        report(0.5)
    assert "3/16 pieces, 1.25 M samples/s" in out.getvalue()
    seen = []
    with progress.make_progress(seen.append) as report:
        report(0.5)
        assert not hasattr(report, "note")  # the caller's own function, untouched
    assert seen == [0.5]
    with progress.make_progress(False) as report:
        assert report is None
