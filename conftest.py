"""Repository-wide pytest settings: hypothesis runs derandomized and without per-example deadlines
(the suite runs on two loaded cores; deadlines there measure the machine, not the code)."""

from hypothesis import settings

settings.register_profile('acds', deadline=None, derandomize=True)
settings.load_profile('acds')
