"""Modelica-style block diagrams of LTI blocks, compiled to one ``control.StateSpace``.

Blocks (``StateSpace``, ``Gain``, ``Sum``, ``PD``, ``PI``, ``Integrator``, ``PadeDelay``,
``BesselFilter``) have named, typed vector connectors. A ``System`` holds blocks, connects
output connectors to input connectors by reference strings, exposes some inputs and outputs
under signal names, checks the diagram (every input driven exactly once, no algebraic loop) and
compiles it with ``control.interconnect``. ``System.to_modelica()`` writes the result as a
Modelica model.

Connector references: ``"block.port"`` (whole port), ``"block.port[2]"`` (1-based element),
``"block.port[name]"`` (element by signal name), ``"block.port[2:4]"`` (1-based, inclusive).

The compiled system's inputs and outputs are the exposed names in the order first exposed; its
states are ``"<block>.<state>"``, blocks in the order of ``System.add`` and each block's states
in its own order (``x[j]``, or ``x[i,j]`` for channel ``i`` of a multi-channel filter/delay).

Example: a position servo on a lightly damped plant, with a 1 ms actuator delay.

>>> import numpy as np
>>> from modelica_like import PD, Gain, PadeDelay, StateSpace, Sum, System
>>> servo = System("servo_demo")
>>> plant = servo.add(StateSpace("plant", A=[[0, 1], [-4, -0.4]], B=[[0], [1]], C=np.eye(2),
...                              D=0, inputs=["torque"], outputs=["angle", "rate"]))
>>> for block in (Sum("err"), Gain("neg", -1.0), PD("ctrl", kp=20.0, kd=3.0),
...               PadeDelay("act", 1e-3, order=2)):
...     _ = servo.add(block)
>>> servo.expose_input("cmd", "err.u1")
>>> servo.connect("plant.y[angle]", "err.u2")     # err = cmd - angle
>>> servo.connect("err.y", "ctrl.x")
>>> servo.connect("plant.y[rate]", "neg.u")       # the error rate is -rate for a constant cmd
>>> servo.connect("neg.y", "ctrl.dx")
>>> servo.connect("ctrl.y", "act.u")
>>> servo.connect("act.y", "plant.u")
>>> servo.expose_output("angle", "plant.y[angle]")
>>> lti = servo.compile()
>>> lti.input_labels, lti.output_labels
(['cmd'], ['angle'])
>>> lti.state_labels
['plant.x[1]', 'plant.x[2]', 'act.x[1]', 'act.x[2]']
>>> print(f"{lti.dcgain():.6f}")                  # kp / (4 + kp)
0.833333
>>> print(servo.to_modelica().splitlines()[0])
model servo_demo "LTI model of modelica_like system 'servo_demo'"
"""

from __future__ import annotations

from .blocks import PD, PI, Block, Gain, Integrator, StateSpace, Sum
from .connectors import Connector
from .errors import ModelError
from .filters import BesselFilter, LowPassFilter, PadeDelay
from .modelica import modelica_identifier
from .system import System

__all__ = [
    "BesselFilter", "Block", "Connector", "Gain", "Integrator", "LowPassFilter", "ModelError", "PadeDelay", "PD",
    "PI", "StateSpace", "Sum", "System", "modelica_identifier",
]
