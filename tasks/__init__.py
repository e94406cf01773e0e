"""Task definitions and benchmark suites (installed as morphosim_gym.tasks)."""
