"""The event simulator: hybrid runs of each scene, judged phase by phase."""
