"""Training: PPO and RecurrentPPO runs from rl-zoo3-style configs, planner-guided warm starts, and sweeps.

The modules import one way, each only from those before it (``tests/test_import_layers.py`` holds them to it):

- ``settings``: the config entry read and every setting validated once (``validate_entry``);
- ``demonstrations``: a planner's demonstrations collected, saved, loaded and re-weighted;
- ``artefacts``: what a run leaves in its folder and how it is read back;
- ``cloning``: behaviour cloning, its minibatches and its one Adam step;
- ``keep_cloning``: cloning steps kept up between PPO's updates (a callback);
- ``pretraining``: the warm start of a run: demonstrations, normalisation, cloning, DAgger;
- ``run``: a training run (``train``, ``resume``);
- ``sweep``: many runs on Ray, each evaluated.

The command lines are ``ekfslam_gym.cli.train`` (``train.py``) and ``ekfslam_gym.cli.sweep``. The agents and
planners they train and imitate live in ``ekfslam_gym.agents``.
"""
