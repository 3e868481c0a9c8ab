"""The jobs layer: one function per command, from files in to files out.

A job takes a small typed spec, reads and checks every input before writing anything,
runs the domain packages on arrays and dataclasses, writes its outputs atomically and
returns a typed result that lists every file it wrote (``written``) and keeps the
in-memory domain result, so a dataset builder can run it thousands of times without
re-reading files. The command line only parses arguments and calls these.
"""
