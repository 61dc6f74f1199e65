"""A worker for the multiprocessing test: runs in a child process started with
"spawn", so everything it gets and returns crosses by pickle."""

import dvrk_ident as di


def fit_in_child(args):
    robot, data, test = args
    result = di.fit(robot, data, method="ols", test=test)
    return robot, data, result
