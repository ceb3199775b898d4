"""Set-up shared by the test modules."""

import signal

# A shell's background job inherits SIGINT ignored, and Python then leaves it
# ignored, as does every process it starts. The Ctrl-C tests interrupt fgf
# processes (and, in test_cluster, this one) as a user's terminal does, so
# Python's own handler is installed here: the processes the tests start then
# get SIGINT's default disposition, however the test command was launched.
signal.signal(signal.SIGINT, signal.default_int_handler)
