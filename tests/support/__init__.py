"""What the tests share beyond conftest.py: scenes they build (fog_scene, xmap_scenes,
random_scenes), the bad-input cases of the fuzz tests and the panel's stub layout."""
