#!/bin/bash
# decode-speed check under the same machine load: before and after, 20 records each, at the same time, one core each
cd /tmp/house
(taskset -c 0 ./run_eval.sh before /tmp/house/timing_before_l20 20 > logs/timing_before.out 2>&1) &
(taskset -c 1 ./run_eval.sh after /tmp/house/timing_after_l20 20 > logs/timing_after.out 2>&1) &
wait
grep -h "tokens/s\|wall_s" logs/timing_before.out logs/timing_after.out
