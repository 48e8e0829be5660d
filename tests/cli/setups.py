"""The command line's shared set-ups: the tiniest study's arguments, and the one-line usage
error a command prints."""
import pytest

from ctxmodels.cli import main

#: A run that takes a second: one short GM-PHD run, no figures.
TINY = ["--scenarios", "mixed-range", "--trackers", "gmphd-context", "--seeds", "1",
        "--duration", "5", "--workers", "1", "--quiet"]


def usage_error(argv, capsys) -> str:
    """Runs the CLI in-process, expects a usage error; returns its one error line."""
    with pytest.raises(SystemExit) as exit_:
        main(argv)
    assert exit_.value.code == 2
    err = capsys.readouterr().err
    assert "Traceback" not in err
    errors = [line for line in err.splitlines() if "error:" in line]
    assert len(errors) == 1, err
    assert errors[0] == err.rstrip("\n").splitlines()[-1]
    return errors[0]
