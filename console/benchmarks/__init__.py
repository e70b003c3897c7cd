"""The console's own benchmarks (``haptable bench console|console-demo|safety``): the top
layer beside ``console.cli``; nothing below imports them. Registered by
``console.core_commands``."""
