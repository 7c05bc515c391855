"""What the tests share beyond conftest.py: scenes they build (fog_scene, xmap_scenes,
random_scenes), the bad-input cases of the fuzz tests, the panel's stub layout and core's
errors as the command line words them (cli_wording)."""
