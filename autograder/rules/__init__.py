"""The rules an answer keeps: no answer taken from the course's library, no call doing the exercise.

Two rules, checked by reading the code with :mod:`ast`, never by running it:

1. **No answer from the library.** An answer reaches no part of ``duckielib`` but those the
   course's own answers of the same notebook use: never the simulator (``duckielib.sim``: the
   robot's firmware, its ground truth and their internals) and never a private name
   (``_name``). The ROS libraries duckielib serves (``rospy``, the message packages, ``tf``,
   ``cv_bridge``, ``duckietown_utils``...) are parts of it too: the nodes of notebooks 08 and 09
   use rospy and message types, so those answers may; a kinematics function may not.
2. **No call doing the exercise.** :data:`FORBIDDEN` lists, for each exercise where one call of
   numpy, OpenCV, Pillow, tf or Duckietown's utilities would do all of it, the libraries its
   notebook says the answer may not use.

An answer's code is every binding of its name anywhere in the notebook (``def``, ``class``,
assignment, import) and what that code references, followed through the notebook: the imports
of every cell (``import duckielib.sim.drivers as d``, ``from numpy import unwrap as u``),
module-level aliases (``m = np``) and the functions and classes the student defined in any
cell, added cells included. A name the course's own cells bind (``bot = VirtualDuckiebot()``) is
followed one step: an answer may use the data those cells hold, not the simulator they made.
What static analysis cannot follow breaks the rule: ``eval``, ``exec``, ``compile``,
``__import__``, importlib, ``getattr`` with a computed name, ``globals()``, ``vars()``,
``sys.modules``, frames, ``__dict__``, a module of the student's own; and so does the student's
code at the top of a cell that could rebind a graded name unseen (``exec``, ``globals()``,
``%run``).

:func:`broken_rules` is pure: it reads the cells it is given and asks only whether a module name
is installed; it imports and runs nothing of the submission.

- :mod:`.reading`: the static reading of a notebook's code (Python's scopes, the notebook's
  bindings across its cells, its magics, what an answer reaches).
- :mod:`.judged`: the two rules judged on that reading, and the sentences for the student.
"""

from autograder.rules.judged import FORBIDDEN, Forbidden, broken_rules, graded_names

__all__ = ["FORBIDDEN", "Forbidden", "broken_rules", "graded_names"]
