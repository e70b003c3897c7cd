"""The plugin API, console part: the console's Textual helpers a plugin's panel may
import (see ``console.plugin_api`` for the whole API). Importing it loads Textual.

What it offers:

- charts: ``Chart`` (a textual-plotext line chart with units; ``summary()`` says what
  it shows) and its ``Series``
- text: ``escape`` (markup-safe text), ``LiteralTable`` (a table that shows its cells
  as written)
- workers and threads: ``LongWork`` (a long job with progress and cancel),
  ``from_thread`` (call the app from a worker thread)
- the session: ``SessionMessage`` (a session event posted to the screen)
- widgets: ``SafetyBar`` (the e-stop and limits bar every screen shows),
  ``ConsoleFooter`` (the footer every screen shows: E-STOP, ``f1-f10`` and ``?`` always)
- panels over a screen: ``LeavesForScreen`` (an F-key closes the panel, or it says why not)
- time left: ``Pace`` (counts done over time: the seconds the rest takes) and
  ``left_words`` ("about 1 min 10 s left": ``console.tui.time_left``), ``seconds_left``
  (from the time so far and the fraction done)
- paths: ``short_path`` (a path as shown: under the home folder with ``~``, else absolute),
  ``PathField`` (a field taking a path or an address: it types every key, ``?`` too),
  ``PathInput`` (a ``PathField`` that, too long for it, shows ``…`` in its middle
  while it has no focus), ``whole_names`` (a path in a given width cut between whole
  names), ``middle_ellipsis`` (a path in a given width, ``…`` in its middle)
- messages: ``said_here`` (an outcome shown on the screen's own status line: logged, and
  a toast only when the screen is not in view; the console's rule, ``console.tui.said``),
  ``status_said`` (whatever a status line now says: an error as ``said_here``, news
  into the log);
  ``lapse`` and ``lapse_if_held`` (a status line true only for a while, or while a run
  holds the outputs, leaves the line when that ends: ``console.tui.lapse``), and
  ``lapse_on_change`` (a line about a state goes when the state changes), ``outputs_held``
  (whether a run or a demo holds the outputs now: the check those lines follow)
- questions: ``AskAgain`` (a key that acts at once on something long or lasting asks
  first: the same key again within a few seconds does it, ``console.tui.ask_again``);
  a timed question holds its status line until it lapses or is answered: the screen's
  status setter is marked ``waits_for_question``, ``answered`` frees the line
  (``console.tui.question_hold``)
- shortening: ``cut_words`` / ``cut_end`` (text within a width, cut after a whole word
  and never inside a bracket it would leave open), ``cut_chars`` (the same for a narrow
  cell, mid-word where it must), ``top_level_seps`` (where a line
  parts into fields outside brackets): ``console.tui.shorten``
- drop-downs: ``Choice`` (a ``Select`` offering its options only, no blank entry: every
  drop-down the console shows is one) and ``chosen`` (a ``Select``'s value as text, ""
  for none: ``console.tui.choice``)
- number fields: ``NumberField`` (a field for a number from ``lo`` to ``hi``: as wide as
  the longest such number, it keeps every character typed, a longer text scrolling in
  it, and its check quotes what it holds: ``console.tui.number_field``)
- check boxes: ``Tick`` (a ``Checkbox`` drawn ``[x]`` / ``[ ]``: its state reads in
  characters, never in shades alone; every check box the console shows is one)
- keys: ``show_keys`` (a list's or table's own keys, Enter first, shown in the footer
  while it has the focus: ``console.tui.focus_keys``); ``name_field`` (a field named
  first in the footer while it has the focus, with what Enter and Esc do there); ``KeptText`` (a line of keys and
  their words wrapped without splitting a key from its word, a number from its unit)
- workers: ``work`` (Textual's ``@work``) and ``run_worker``, under the console's rule
  for a failure nobody expected (``console.tui.workers``: said on the screen, the
  outputs stopped, the console goes on)
"""

from __future__ import annotations

from console.tui.ask_again import AskAgain
from console.tui.charts import Chart, Series
from console.tui.choice import Choice, chosen
from console.tui.focus_keys import name_field, show_keys
from console.tui.kept_text import KeptText
from console.tui.lapse import lapse, lapse_if_held, lapse_on_change, outputs_held
from console.tui.long_work import LongWork
from console.tui.narrow import ConsoleFooter
from console.tui.number_field import NumberField
from console.tui.panels import LeavesForScreen
from console.tui.path_field import PathField, PathInput, middle_ellipsis, whole_names
from console.tui.question_hold import answered, waits_for_question
from console.tui.safety_bar import SafetyBar
from console.tui.said import said_here, status_said
from console.tui.session_messages import SessionMessage
from console.tui.shorten import cut_chars, cut_end, cut_words, top_level_seps
from console.tui.text import LiteralTable, escape
from console.tui.ticks import Tick
from console.tui.time_left import Pace, left_words, seconds_left
from console.tui.util import from_thread, short_path
from console.tui.workers import run_worker, work

__all__ = [
    "AskAgain",
    "Chart",
    "Choice",
    "chosen",
    "Series",
    "ConsoleFooter",
    "LeavesForScreen",
    "KeptText",
    "LiteralTable",
    "LongWork",
    "NumberField",
    "SafetyBar",
    "SessionMessage",
    "escape",
    "said_here",
    "status_said",
    "lapse",
    "lapse_if_held",
    "outputs_held",
    "lapse_on_change",
    "answered",
    "waits_for_question",
    "show_keys",
    "name_field",
    "from_thread",
    "short_path",
    "PathField",
    "PathInput",
    "middle_ellipsis",
    "whole_names",
    "Pace",
    "left_words",
    "seconds_left",
    "Tick",
    "cut_chars",
    "cut_end",
    "cut_words",
    "top_level_seps",
    "work",
    "run_worker",
]
