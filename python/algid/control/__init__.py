"""Control: the tracking controller that identifies its plant while it runs
(:mod:`.controller`), its pole-placement law (:mod:`.control_law`), the gate that admits an
estimate to the law (:mod:`.estimate_gate`), the held input of a rig (:mod:`.held_input`), the
references (:mod:`.trajectories`, :mod:`.positioning`), the per-step log
(:mod:`.controller_log`), and ``algid demo``, the closed loop on the simulator (:mod:`.demo`)."""
