"""The console's Textual app (``console.tui.app``) and its pieces."""

from console.tui.glue import install as _glue_numbers_to_units

_glue_numbers_to_units()  # a number never wraps apart from its unit or label (``glue``)
