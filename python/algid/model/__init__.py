"""The model: the n-DOF mass-spring-damper chain of eq. 1 (:mod:`.chain`), its modes
(:mod:`.modal`) and its frequency response (:mod:`.frf`)."""
