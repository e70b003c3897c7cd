"""The console's own benchmarks (``haptable bench console|console-demo|safety``): the top
layer beside ``console.cli.main``; nothing below imports them. Registered by
``console.cli.core_commands``."""
