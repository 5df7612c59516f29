"""A package's own msg/ and srv/ folders import as ``<package>.msg`` and ``.srv``, as on a robot."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

FOO = "Header header\ngeometry_msgs/Twist twist\nBar[] bars\nuint8 MODE_A=1\n"
BAR = "duckietown_msgs/Vector2D v\nstring label\n"
CHECK = "Foo foo\n---\nbool ok\n"
#: The md5 sum genmsg computes for FOO.
FOO_MD5 = "0ed023590003bf38f2225c28160aecfe"


def make_package(root: Path, name: str = "my_pkg") -> Path:
    package = root / name
    (package / "msg").mkdir(parents=True)
    (package / "srv").mkdir()
    (package / "msg" / "Foo.msg").write_text(FOO)
    (package / "msg" / "Bar.msg").write_text(BAR)
    (package / "srv" / "Check.srv").write_text(CHECK)
    return package


def run_python(args, cwd: Path) -> str:
    result = subprocess.run(
        [sys.executable, *args], capture_output=True, text=True, check=False, cwd=cwd
    )
    assert result.returncode == 0, result.stderr
    return result.stdout


NODE = """
import duckielib.ros
from my_pkg.msg import Bar, Foo
from my_pkg.srv import Check, CheckRequest
foo = Foo(bars=[Bar(label="x")])
print(Foo._type, Foo._md5sum, Foo.MODE_A, Foo.from_bytes(foo.to_bytes()) == foo)
print(Check._type, CheckRequest().foo.twist.linear.x, Foo.__module__)
"""


def test_a_package_next_to_the_node_imports(tmp_path):
    make_package(tmp_path)
    (tmp_path / "node.py").write_text(NODE)
    out = run_python(["node.py"], cwd=tmp_path)
    assert out.split("\n")[:2] == [
        f"my_pkg/Foo {FOO_MD5} 1 True",
        "my_pkg/Check 0.0 duckielib.messages.my_pkg.msg",
    ]


def test_a_package_in_the_current_folder_imports(tmp_path):
    make_package(tmp_path / "work")
    (tmp_path / "scripts").mkdir()
    (tmp_path / "scripts" / "node.py").write_text(NODE)
    out = run_python([str(tmp_path / "scripts" / "node.py")], cwd=tmp_path / "work")
    assert out.startswith(f"my_pkg/Foo {FOO_MD5} 1 True\n")


def test_a_generated_module_is_left_alone(tmp_path):
    package = make_package(tmp_path)
    (package / "msg" / "__init__.py").write_text("REAL = True\n")
    out = run_python(
        ["-c", "import duckielib.ros, my_pkg.msg; print(getattr(my_pkg.msg, 'REAL', False))"],
        cwd=tmp_path,
    )
    assert out.split() == ["True"]


def test_an_unknown_field_type_is_named(tmp_path):
    package = make_package(tmp_path, "broken_pkg")
    (package / "msg" / "Bar.msg").write_text("nope_msgs/Thing thing\n")
    out = run_python(
        [
            "-c",
            "from duckielib import messages\n"
            "from duckielib.errors import MessageDefinitionError\n"
            "try:\n"
            "    messages.add_package('broken_pkg', 'broken_pkg')\n"
            "except MessageDefinitionError as error:\n"
            "    print(error)\n"
            "print('broken_pkg/Foo' in messages.REGISTRY.messages)\n",
        ],
        cwd=tmp_path,
    )
    assert out.split("\n")[:2] == [
        "The field 'thing' of broken_pkg/Bar has the type 'nope_msgs/Thing', "
        "which is not a known message type.",
        "False",
    ]


ADD_TWICE = """
from duckielib import messages
from duckielib.errors import MessageDefinitionError
module = messages.add_package("once_pkg", "once_pkg")
print(messages.add_package("once_pkg", "once_pkg") is module, module.msg.Foo._md5sum)
print(module.srv.CheckResponse(ok=True).ok, "once_pkg/Check" in messages.service_types())
print(messages.add_package("once_pkg", "copy/once_pkg") is module)  # the same definitions
for name, folder in [("once_pkg", "elsewhere/once_pkg"), ("std_msgs", "once_pkg")]:
    try:
        messages.add_package(name, folder)
    except MessageDefinitionError as error:
        print(str(error).split(" (")[0])
"""


def test_a_package_is_added_once(tmp_path):
    make_package(tmp_path, "once_pkg")
    make_package(tmp_path / "copy", "once_pkg")
    other = make_package(tmp_path / "elsewhere", "once_pkg")
    (other / "msg" / "Bar.msg").write_text("string label\nint32 count\n")
    out = run_python(["-c", ADD_TWICE], cwd=tmp_path)
    assert out.split("\n")[:5] == [
        f"True {FOO_MD5}",
        "True True",
        "True",
        "The package once_pkg is defined already",
        "The package std_msgs is defined already",
    ]
