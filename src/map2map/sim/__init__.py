"""A fast 2-D robot simulator replacing the thesis's Gazebo runs (thesis 4.1).

Modules, in the order data flows through a run:

* :mod:`.raycast` - exact Amanatides-Woo ray casting on grids (numba);
* :mod:`.lidar` - the LDS-01 laser scanner and its beam model;
* :mod:`.world` - the plan plus optional furniture and walking people;
* :mod:`.robot` - TurtleBot3 Waffle Pi differential drive with collisions;
* :mod:`.odometry` - wheel odometry from encoder ticks, UMBmark errors and slip;
* :mod:`.mapping` - the oracle mapper (log-odds grid at the true poses);
* :mod:`.explore` - explore_lite-style frontier exploration and route following;
* CARMEN log files (write, read, replay) live in :mod:`map2map.robotlog.carmen`;
* :mod:`.runner` - :func:`simulate`, tying it all together.
"""
