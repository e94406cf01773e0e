"""Gymnasium environments (installed as morphosim_gym.envs)."""
