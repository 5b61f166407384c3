"""The reactive robot: a teleo-reactive rule list, run every cycle, instead of a sequencer.

`rules` is the rule list; `route` follows a route leg, `car` calls, boards and leaves cars;
`state` is what the rules sense each cycle and the little they keep.
"""
