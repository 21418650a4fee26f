//! Mission tests: the state machine driven with the kinematic double in hand-made worlds.
