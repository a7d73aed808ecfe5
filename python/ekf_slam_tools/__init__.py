"""Python tools of the ekf_slam package: SE(2) helpers (se2), consistency
statistics (stats), occupancy-grid geometry (grids), programs in a
pseudo-terminal for the tests (terminal), the simulator's worlds
and map images (worlds), trajectory files (trajectories) and the
simulated-run monitor (sim_monitor). The scripts
in tools/ are thin entry points over these modules; source the workspace
(`source .build/setup.bash`) to import them."""
