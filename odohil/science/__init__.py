"""Layer 1, the science core: model, simulator, closed forms, observables,
estimators, pose from floor marks and planner. Pure numpy/scipy, no I/O."""
