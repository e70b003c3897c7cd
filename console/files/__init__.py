"""Files: where they live, written atomically, read bounded, cache files keyed by their
inputs, npz read safely, and the vibration map's format. Standard library and numpy only."""
