"""The P_D record the hypothesiser and the deleter keep per track
(``ctxmodels.stonesoup.jpda._pd_record``): entries valid only at the timestamp they were
recorded at, dropped at a restart and with their track, kept through a pickle."""
import datetime
import gc
import pickle

from stonesoup.types.track import Track

from ctxmodels.stonesoup.jpda._pd_record import PDRecord

T0 = datetime.datetime(2025, 1, 1)
T1 = T0 + datetime.timedelta(seconds=1)


def test_entries_are_read_at_their_timestamp_and_restart_clears_them():
    record, track = PDRecord(), Track()
    record.record(track, 1, T0, 0.9, restart=False)
    record.record(track, 2, T1, 0.5, restart=False)
    assert record.get(track, 1, T0) == 0.9 and record.get(track, 2, T1) == 0.5
    assert record.get(track, 1, T1) is None  # the state there has another time now
    assert record.get(track, 3, T1) is None and record.get(Track(), 1, T0) is None
    record.record(track, 3, T1, 0.25, restart=True)  # a detection came before index 3
    assert record.get(track, 1, T0) is None and record.get(track, 3, T1) == 0.25


def test_a_dropped_track_drops_its_entries():
    record, track = PDRecord(), Track()
    record.record(track, 1, T0, 0.9, restart=False)
    assert len(record) == 1
    del track
    gc.collect()
    assert len(record) == 0


def test_a_pickle_keeps_the_entries_of_the_tracks_pickled_with_it():
    record, track = PDRecord(), Track()
    record.record(track, 1, T0, 0.9, restart=False)
    copied_record, copied_track = pickle.loads(pickle.dumps((record, track)))
    assert copied_record.get(copied_track, 1, T0) == 0.9
    assert copied_record.get(track, 1, T0) is None  # keyed by identity: the copy's track
