"""Start the sandbox's server: ``python autograder/sandbox/inside --serve CELL_SECONDS``.

Run as a folder, this file's folder comes first on ``sys.path``; its parent takes that place,
so the package imports itself as ``inside`` (its modules import one another relatively). In
the sandbox that parent holds this package alone: nothing else of the grader is there to
import. The zygote takes that entry out of the kernels' path.
"""

import sys
from pathlib import Path

if __package__ in (None, ""):
    sys.path[0] = str(Path(__file__).resolve().parent.parent)
    from inside.serve import main  # type: ignore[import-not-found]
else:  # python -m autograder.sandbox.inside
    from .serve import main

main()
