"""What runs inside the sandbox: the server, the notebook's run, the guard, the kernel zygote.

- :mod:`.serve`: the server the grader talks to; runs the notebooks it is sent, one by one.
- :mod:`.wire`: the messages between the grader and the server, both ends.
- :mod:`.notebook`: one notebook's run in nbclient, with the guard and the grader's tests.
- :mod:`.guard`: what goes into the kernel before the first cell, as real Python.
- :mod:`.zygote`: the process that forks each notebook's kernel with its imports done.
- :mod:`.seam`: the private parts of jupyter_client and nbclient relied on, listed and checked.
- :mod:`.processes`: the processes a notebook leaves behind.

Every module here imports only the standard library at load time (``tests/test_purity.py``
checks it): the server starts in a few milliseconds and forks the zygote before anything else
is imported. Started as ``python autograder/sandbox/inside``, the package is ``inside``; in the
grader, ``autograder.sandbox.inside``.
"""
