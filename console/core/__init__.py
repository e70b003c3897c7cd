"""The lowest layer: types, errors and words, the plugin contracts and hook specs, option
and schema checks, and the OS scheduling calls. Imports nothing above it."""
