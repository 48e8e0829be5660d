"""The paper's radar–lidar experiment: scenarios, trackers, metrics, runner."""
