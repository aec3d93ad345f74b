cd /work/s23-need9
while kill -0 $(cat /tmp/s23/need9/chain.pid) 2>/dev/null; do sleep 5; done
for a in "q01p1 0.1 1" "q005p1 0.05 1" "q1p06any 1 0.6 any" "q1p06s1 1 0.6 edge 1" "q025p05 0.25 0.5" "q01p075 0.1 0.75" "q1p03 1 0.3" "q025p075s1 0.25 0.75 edge 1" "q005p075 0.05 0.75"; do
  set -- $a
  PYTHONPATH=$PWD nice -n 5 python /tmp/s23/need9/need.py $1 0-23 $2 $3 $4 $5 > /tmp/s23/need9/$1.log 2>&1
done
