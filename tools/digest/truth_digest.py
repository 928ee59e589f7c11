#!/usr/bin/env python3
"""The digest of a rig log's TRUTH stream: SHA-256 over every TRUTH message's bytes in log order,
and their count. Two runs whose digests agree flew the same truth, byte for byte (a refactoring
that keeps behaviour keeps the digest of the same scenario and seed; lockstep and in-process
runs of one scenario and seed have the same digest).

Usage: truth_digest.py LOG [LOG...]   (prints "<log> <first 16 hex digits> <messages>" per log)

  build/bin/rig run rig_configs/id_doublet_train_fast.yaml --clock inprocess --seed 1 --log /tmp/t.lcmlog
  tools/digest/truth_digest.py /tmp/t.lcmlog
"""
import hashlib
import struct
import sys

SYNC = 0xEDA1DA01  # LCM log event marker
CHANNEL = "TRUTH"  # the contract's name (contract/channels.h)


def truth_digest(path):
    digest = hashlib.sha256()
    count = 0
    with open(path, "rb") as f:
        data = f.read()
    i = 0
    while i + 28 <= len(data):
        sync, _event, _utime, channel_len, data_len = struct.unpack(">IqqII", data[i:i + 28])
        if sync != SYNC:
            sys.exit("%s: no LCM event at byte %d (a damaged log?)" % (path, i))
        end = i + 28 + channel_len + data_len
        if end > len(data):
            break  # a last event cut short: what came before it counts
        if data[i + 28:i + 28 + channel_len].decode(errors="replace") == CHANNEL:
            digest.update(data[i + 28 + channel_len:end])
            count += 1
        i = end
    return digest.hexdigest()[:16], count


def main():
    if len(sys.argv) < 2:
        sys.exit(__doc__)
    for path in sys.argv[1:]:
        d, n = truth_digest(path)
        print(path, d, n)


if __name__ == "__main__":
    main()
