"""The type stubs (torsion/__init__.pyi) list what the module has, and the module what they list."""

import ast
import pathlib

import torsion

PUBLIC_CLASSES = ["Frame", "Material", "State", "Body", "NodeSet", "Hand", "RigidBody", "World",
                  "Contacts"]


def stub_classes():
    tree = ast.parse((pathlib.Path(torsion.__file__).parent / "__init__.pyi").read_text())
    classes = {}
    for node in tree.body:
        if isinstance(node, ast.ClassDef):
            names = set()
            for item in node.body:
                if isinstance(item, (ast.FunctionDef, ast.AnnAssign)):
                    names.add(item.name if isinstance(item, ast.FunctionDef) else item.target.id)
            classes[node.name] = names
    return classes


def test_every_public_class_member_is_in_the_stubs_and_every_stub_member_exists():
    stubs = stub_classes()
    for name in PUBLIC_CLASSES:
        cls = getattr(torsion, name)
        runtime = {m for m in dir(cls) if not m.startswith("_")}
        listed = {m for m in stubs[name] if not m.startswith("_")}
        assert runtime == listed, (name, runtime ^ listed)


def test_every_name_the_package_exports_is_in_the_stubs_and_every_stub_name_exists():
    tree = ast.parse((pathlib.Path(torsion.__file__).parent / "__init__.pyi").read_text())
    listed = set()
    for node in tree.body:
        if isinstance(node, (ast.ClassDef, ast.FunctionDef)):
            listed.add(node.name)
        elif isinstance(node, ast.AnnAssign):
            listed.add(node.target.id)
    assert set(torsion.__all__) == listed, set(torsion.__all__) ^ listed
    for name in torsion.__all__:
        assert hasattr(torsion, name), name


def test_every_public_binding_has_a_docstring():
    for name in PUBLIC_CLASSES:
        cls = getattr(torsion, name)
        assert cls.__doc__, name
    for method in ["from_scene", "step", "save_state", "restore_state", "add_body", "add_node_set",
                   "add_hand", "add_rigid_body", "add_ground", "render", "write_vtk", "contacts"]:
        assert getattr(torsion.World, method).__doc__, method
    for method in ["set_pose", "set_velocity", "apply_force", "apply_torque",
                   "set_kinematic_target"]:
        assert getattr(torsion.RigidBody, method).__doc__, method
    for prop in ["gravity", "dt"]:
        assert getattr(torsion.World, prop).__doc__, prop
    assert torsion.data_path.__doc__
