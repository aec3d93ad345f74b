cd /work/s23-need9
while kill -0 $(cat /tmp/s23/need9/cur.pid) 2>/dev/null; do sleep 5; done
for a in "q1p06pred 1 0.6 pred" "q005p045pred 0.05 0.45 pred" "q005p045 0.05 0.45" "q1p08pred 1 0.8 pred" "q01p075 0.1 0.75"; do
  set -- $a
  PYTHONPATH=$PWD nice -n 5 python /tmp/s23/need9/need.py $1 0-23 $2 $3 $4 $5 > /tmp/s23/need9/$1.log 2>&1
done
