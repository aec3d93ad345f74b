cd /work/s23-need9
for a in "q1p06 1 0.6" "q1p08 1 0.8" "q025p1 0.25 1" "q025p075 0.25 0.75" "q1p045 1 0.45" "q1p1 1 1"; do
  set -- $a
  PYTHONPATH=$PWD nice -n 5 python /tmp/s23/need9/need.py $1 0-23 $2 $3 > /tmp/s23/need9/$1.log 2>&1
done
