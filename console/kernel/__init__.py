"""The safety kernel: one small process per table owns the outputs.

It alone opens the audio driver and the relay board, holds the safety gate (immutable
limits built from the profile when it starts) and the output scheduler, synthesises live
streams from their parameters, and takes plans, stream parameters and relay requests from
its clients (the console, demos, studies, CLI commands) over a private socket, checking
each on arrival. Its audio callback never waits on a client. An e-stop latches: nothing
plays until an operator resets it, and an e-stop that arrives before any output opened
is remembered for the table.

Modules (this package's ``__init__`` imports nothing: `haptable estop` loads only the
standard-library ones):

- ``tables``: a table's identity and files in the private runtime directory, the latch;
- ``line_server`` / ``private_dir``: one-line commands over private Unix sockets;
- ``operator``: who may reset an e-stop (an operator, never a program);
- ``shell``: `haptable estop` and `haptable reset`, standard library only;
- ``wire``: the framed messages between clients and the kernel;
- ``scheduler``: plans, streams and relay steps, block by block, inside the kernel;
- ``table``: the drivers, the gate and the scheduler of a table in one process;
- ``requests``: what a client may ask, each checked before it reaches the scheduler;
- ``server``: the kernel process (``python -m console.kernel``);
- ``spawn``: starting it for a client; ``client``: what a process holds instead of
  outputs (``Outputs``);
- ``memory_lock``: the kernel's memory kept in RAM while it plays in real time.
"""
