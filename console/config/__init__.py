"""A table's configuration: the profile and its sections, the plugin manager, the files
kept per profile and the signal library."""
