"""A Python participant as a rig process of its own over LCM, started by the launcher for the
scenario's `participants` section in lockstep and real time, as it starts the rig's own processes:

    python3 -m nimble_rig.node --name controller --scenario RESOLVED.yaml --lcm-url URL

It loads the class the section names (nimble_rig/participant.py), checks it against the rig's
contract, and flies it in place of that process: heartbeat, health and faults on LCM like the rig's
processes, lockstep acknowledgements, and its step() at its rate. An exception in step() ends the
process (exit code 4) after a FATAL fault naming it with the simulated time, which the launcher
puts in the run's result.
"""

import sys

from . import _rig


def main(argv=None):
    """Runs the node with `argv` (default: the command line's) and returns its exit code."""
    return _rig._run_node(list(sys.argv[1:] if argv is None else argv))


if __name__ == "__main__":
    sys.exit(main())
