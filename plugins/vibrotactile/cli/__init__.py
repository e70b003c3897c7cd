"""``haptable frf``, ``tables``, ``flow`` and ``point``: one module per command
(``frf``, ``tables``, ``flow`` with ``point``), what they share in ``common``."""
