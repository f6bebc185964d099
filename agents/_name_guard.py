"""Refuses the top-level name ``agents``: the checkout's agents/ folder is the package ``ekfslam_gym.agents``
(setup.py maps it there), and importing it by a second name would make a second copy of every class (two
``Agent`` types, ``isinstance`` failing across them). ``agents/__init__.py`` imports this first."""

if __package__ != "ekfslam_gym.agents":
    raise ImportError(
        f"the checkout's agents/ folder installs as ekfslam_gym.agents: import that, not {__package__}"
    )
