"""Signals in volts: waveform blocks, the signal language (syntax, parser, checks), the
named test stimuli and the live streams synthesised from their parameters. Pure numpy."""
