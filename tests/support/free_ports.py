#!/usr/bin/python3
"""Prints N free TCP ports on the loopback (default 2), space-separated.

The ports are bound together (so they differ), closed, and only then printed: a caller that reads
them with $(...) starts its servers after this process has let them go. Reading them from a
process substitution instead races the interpreter's exit, and a server that binds first finds
the port in use.
"""
import socket
import sys

count = int(sys.argv[1]) if len(sys.argv) > 1 else 2
socks = [socket.socket() for _ in range(count)]
for s in socks:
    s.bind(("127.0.0.1", 0))
ports = [s.getsockname()[1] for s in socks]
for s in socks:
    s.close()
print(*ports)
