cd /work/s23-need9
while kill -0 $(cat /tmp/s23/need9/cur.pid) 2>/dev/null; do sleep 5; done
for a in "q1p06s1 1 0.6 edge 1" "q005p075 0.05 0.75" "q005p045 0.05 0.45" "q01p075 0.1 0.75" "q005p045any 0.05 0.45 any" "q025p05 0.25 0.5" "q1p03 1 0.3"; do
  set -- $a
  PYTHONPATH=$PWD nice -n 5 python /tmp/s23/need9/need.py $1 0-23 $2 $3 $4 $5 > /tmp/s23/need9/$1.log 2>&1
done
