"""What the hostile-input tests share: the checks that an error names its argument, and the
small set-ups several of them build (a navigation track, the paper's sensor models)."""
import datetime

import pytest

from ctxmodels import NavigationTrack

T0 = datetime.datetime(2026, 1, 1)


def names_argument(call, exception, argument):
    with pytest.raises(exception) as info:
        call()
    assert str(info.value).startswith(f"{argument}:"), str(info.value)
    return str(info.value)


def names(call, exception, argument):
    """`call()` raises `exception` (or one of ctxmodels' subclasses of it, never a
    PanicException, which is a BaseException) and the message starts by naming `argument`."""
    try:
        call()
    except BaseException as err:  # noqa: B036 — a panic must fail here, not escape
        assert isinstance(err, exception), f"{type(err).__name__}: {err}"
        assert type(err) is exception or type(err).__module__ == "ctxmodels.errors", \
            f"{type(err).__name__}: {err}"
        assert str(err).startswith(f"{argument}:"), str(err)
        return str(err)
    raise AssertionError(f"no {exception.__name__} naming {argument}")


def _navigation():
    stamps = [T0 + datetime.timedelta(seconds=s) for s in range(3)]
    return NavigationTrack(timestamps=stamps, positions=[[0.0, 0.0], [1.0, 0.0], [2.0, 0.0]],
                           headings=[0.0, 0.0, 0.0])


def _paper_models():
    from ctxmodels.experiment.sensors import paper_sensor_models
    paper = paper_sensor_models()
    return {"radar": paper["radar"], "lidar": paper["lidar"]}
