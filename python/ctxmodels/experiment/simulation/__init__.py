"""The seeded simulator behind :mod:`ctxmodels.experiment.scenarios` (the experiment's
ground truth), one module per concept:

* :mod:`.paths`: paths of straight legs and turns (:class:`~.paths.PathBuilder`);
* :mod:`.motion`: how vessels and the ego move along them;
* :mod:`.scene`: what a scenario is made of (vessels, static objects, land);
* :mod:`.radar`, :mod:`.lidar`: the simulated sensors, their clutter and land returns;
* :mod:`.geometry`: angles, polar coordinates, land and line of sight;
* :mod:`.scans`: what a scan is, scan timing, how a detection is typed;
* :mod:`.run`: :func:`~.run.simulate`, a layout and a seed → a :class:`~.run.ScenarioRun`;
* :mod:`.layouts`: the three scenarios and :func:`~.layouts.make_scenario`;
* :mod:`.truths`: named sensor truths (calibrated, stress).

Import the public names from :mod:`ctxmodels.experiment.scenarios`. Nothing here may
import ``ctxmodels._core`` or the context models: it is what they are judged against.
"""
