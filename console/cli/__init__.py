"""The ``haptable`` command: ``entry`` (e-stop and reset before anything heavy), ``main``
(the CLI) and the core and signal commands."""
