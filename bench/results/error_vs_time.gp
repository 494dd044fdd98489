$path0 << EOD
0.272458 3.58048 -
0.924072 0.843455 -
3.39994 0.210066 -
13.2063 0.055256 -
EOD
$pm0 << EOD
0.895437 0.00726063 preview
2.83784 0.00204104 final
2.15906 0.00362029 -
2.09625 0.00408511 -
5.2086 0.00153774 -
2.49571 0.00234617 -
4.10225 0.00191446 -
3.62906 0.00199437 -
2.60581 0.00216382 -
4.6039 0.00160746 -
6.97141 0.00130031 -
EOD
$pmcurve0 << EOD
0.895437 0.00726063 preview
2.09625 0.00408511 -
2.15906 0.00362029 -
2.49571 0.00234617 -
2.60581 0.00216382 -
2.83784 0.00204104 final
3.62906 0.00199437 -
4.10225 0.00191446 -
4.6039 0.00160746 -
5.2086 0.00153774 -
6.97141 0.00130031 -
EOD
$front0 << EOD
0.272458 3.58048 -
0.895437 0.00726063 preview
2.09625 0.00408511 -
2.15906 0.00362029 -
2.49571 0.00234617 -
2.60581 0.00216382 -
2.83784 0.00204104 final
3.62906 0.00199437 -
4.10225 0.00191446 -
4.6039 0.00160746 -
5.2086 0.00153774 -
6.97141 0.00130031 -
EOD
$presets0 << EOD
0.895437 0.00726063 preview
2.83784 0.00204104 final
EOD
$path1 << EOD
0.1768 0.226761 -
0.661215 0.0488014 -
2.39913 0.0107455 -
10.2404 0.00262325 -
EOD
$pm1 << EOD
0.565349 0.00592378 preview
1.39517 0.00153427 final
1.16463 0.00269059 -
1.2066 0.00189959 -
1.91241 0.00138978 -
1.15236 0.00187647 -
1.89802 0.00143429 -
1.71722 0.00147898 -
0.977029 0.00179515 -
1.6413 0.00106498 -
2.57127 0.000835674 -
EOD
$pmcurve1 << EOD
0.565349 0.00592378 preview
0.977029 0.00179515 -
1.39517 0.00153427 final
1.6413 0.00106498 -
2.57127 0.000835674 -
EOD
$front1 << EOD
0.1768 0.226761 -
0.565349 0.00592378 preview
0.977029 0.00179515 -
1.39517 0.00153427 final
1.6413 0.00106498 -
2.57127 0.000835674 -
EOD
$presets1 << EOD
0.565349 0.00592378 preview
1.39517 0.00153427 final
EOD
$path2 << EOD
0.0887671 7.44829 -
0.263743 2.70614 -
1.07137 0.842645 -
3.60443 0.111139 -
13.9236 0.0386054 -
EOD
$pm2 << EOD
0.187903 0.0499847 preview
0.43315 0.0328425 final
0.398248 0.0330753 -
0.258352 0.0652114 -
1.26869 0.0445184 -
0.429902 0.0340661 -
0.441307 0.0301873 -
0.462747 0.0328425 -
0.463309 0.0328425 -
0.59153 0.0311833 -
0.84766 0.0318132 -
EOD
$pmcurve2 << EOD
0.187903 0.0499847 preview
0.398248 0.0330753 -
0.43315 0.0328425 final
0.441307 0.0301873 -
EOD
$front2 << EOD
0.0887671 7.44829 -
0.187903 0.0499847 preview
0.398248 0.0330753 -
0.43315 0.0328425 final
0.441307 0.0301873 -
EOD
$presets2 << EOD
0.187903 0.0499847 preview
0.43315 0.0328425 final
EOD
$path3 << EOD
0.393073 0.114523 -
1.22992 0.0260191 -
4.41613 0.00616203 -
18.2757 0.00151158 -
EOD
$pm3 << EOD
1.04248 0.0140019 preview
1.90036 0.00365079 final
1.64873 0.00543468 -
1.95247 0.00716968 -
2.41827 0.00191733 -
1.40992 0.00387868 -
2.89676 0.00357323 -
2.50266 0.0036777 -
1.61279 0.00372836 -
2.50564 0.00290318 -
3.57256 0.00259436 -
EOD
$pmcurve3 << EOD
1.04248 0.0140019 preview
1.40992 0.00387868 -
1.61279 0.00372836 -
1.90036 0.00365079 final
2.41827 0.00191733 -
EOD
$front3 << EOD
0.393073 0.114523 -
1.04248 0.0140019 preview
1.40992 0.00387868 -
1.61279 0.00372836 -
1.90036 0.00365079 final
2.41827 0.00191733 -
18.2757 0.00151158 -
EOD
$presets3 << EOD
1.04248 0.0140019 preview
1.90036 0.00365079 final
EOD
$path4 << EOD
0.356448 0.90606 -
1.36657 0.216089 -
4.92997 0.052179 -
18.25 0.0131238 -
EOD
$pm4 << EOD
1.24434 0.00624456 preview
2.72723 0.00247423 final
2.37189 0.0030909 -
2.44235 0.00287485 -
3.6099 0.00226832 -
1.83516 0.00324745 -
4.30887 0.00204345 -
3.58269 0.00239171 -
2.07243 0.0027241 -
3.50533 0.00224567 -
4.57984 0.00215881 -
EOD
$pmcurve4 << EOD
1.24434 0.00624456 preview
1.83516 0.00324745 -
2.07243 0.0027241 -
2.72723 0.00247423 final
3.50533 0.00224567 -
4.30887 0.00204345 -
EOD
$front4 << EOD
0.356448 0.90606 -
1.24434 0.00624456 preview
1.83516 0.00324745 -
2.07243 0.0027241 -
2.72723 0.00247423 final
3.50533 0.00224567 -
4.30887 0.00204345 -
EOD
$presets4 << EOD
1.24434 0.00624456 preview
2.72723 0.00247423 final
EOD
$path5 << EOD
0.814867 0.249629 -
3.18126 0.0462991 -
12.6694 0.0189438 -
48.1594 0.00506844 -
EOD
$pm5 << EOD
2.61817 0.00300265 preview
9.09257 0.00178388 final
6.78873 0.00190827 -
9.54039 0.00186332 -
9.81384 0.00169894 -
8.00378 0.00237934 -
12.7101 0.00147285 -
11.2679 0.00157594 -
8.46122 0.00191736 -
15.4173 0.00173077 -
26.3753 0.00170837 -
EOD
$pmcurve5 << EOD
2.61817 0.00300265 preview
6.78873 0.00190827 -
9.09257 0.00178388 final
9.81384 0.00169894 -
11.2679 0.00157594 -
12.7101 0.00147285 -
EOD
$front5 << EOD
0.814867 0.249629 -
2.61817 0.00300265 preview
6.78873 0.00190827 -
9.09257 0.00178388 final
9.81384 0.00169894 -
11.2679 0.00157594 -
12.7101 0.00147285 -
EOD
$presets5 << EOD
2.61817 0.00300265 preview
9.09257 0.00178388 final
EOD
$path6 << EOD
0.388457 0.449979 -
1.15386 0.120524 -
4.11713 0.0302586 -
15.7655 0.00737265 -
EOD
$pm6 << EOD
0.945496 0.0306002 preview
2.92754 0.00723439 final
2.29632 0.0123063 -
2.2404 0.0084131 -
5.60479 0.00680159 -
2.4447 0.00733066 -
3.99159 0.00720267 -
3.30063 0.00722328 -
2.77964 0.00726395 -
4.54292 0.00425781 -
7.28404 0.0025595 -
EOD
$pmcurve6 << EOD
0.945496 0.0306002 preview
2.2404 0.0084131 -
2.4447 0.00733066 -
2.77964 0.00726395 -
2.92754 0.00723439 final
3.30063 0.00722328 -
3.99159 0.00720267 -
4.54292 0.00425781 -
7.28404 0.0025595 -
EOD
$front6 << EOD
0.388457 0.449979 -
0.945496 0.0306002 preview
2.2404 0.0084131 -
2.4447 0.00733066 -
2.77964 0.00726395 -
2.92754 0.00723439 final
3.30063 0.00722328 -
3.99159 0.00720267 -
4.54292 0.00425781 -
7.28404 0.0025595 -
EOD
$presets6 << EOD
0.945496 0.0306002 preview
2.92754 0.00723439 final
EOD
$path7 << EOD
0.867656 3.67449 -
3.33897 0.911427 -
12.5903 0.224384 -
EOD
$pm7 << EOD
2.83686 0.00783786 preview
7.30037 0.00337849 final
5.19917 0.00426804 -
5.16149 0.00576287 -
13.4465 0.00277561 -
5.81643 0.00373902 -
8.45392 0.003252 -
7.29387 0.0033099 -
6.99134 0.00337373 -
11.8869 0.00307524 -
17.9653 0.00288759 -
EOD
$pmcurve7 << EOD
2.83686 0.00783786 preview
5.16149 0.00576287 -
5.19917 0.00426804 -
5.81643 0.00373902 -
6.99134 0.00337373 -
7.29387 0.0033099 -
8.45392 0.003252 -
11.8869 0.00307524 -
13.4465 0.00277561 -
EOD
$front7 << EOD
0.867656 3.67449 -
2.83686 0.00783786 preview
5.16149 0.00576287 -
5.19917 0.00426804 -
5.81643 0.00373902 -
6.99134 0.00337373 -
7.29387 0.0033099 -
8.45392 0.003252 -
11.8869 0.00307524 -
13.4465 0.00277561 -
EOD
$presets7 << EOD
2.83686 0.00783786 preview
7.30037 0.00337849 final
EOD
$path8 << EOD
0.610337 0.220313 -
2.36537 0.0486853 -
10.2434 0.0106704 -
EOD
$pm8 << EOD
1.77377 0.00597096 preview
3.50788 0.00141728 final
2.77646 0.00241379 -
3.27028 0.00183506 -
4.19018 0.00124441 -
2.73592 0.00176747 -
5.00557 0.0012979 -
4.52764 0.00139147 -
3.45404 0.00139623 -
4.87832 0.000937513 -
7.7762 0.00073071 -
EOD
$pmcurve8 << EOD
1.77377 0.00597096 preview
2.73592 0.00176747 -
3.45404 0.00139623 -
4.19018 0.00124441 -
4.87832 0.000937513 -
7.7762 0.00073071 -
EOD
$front8 << EOD
0.610337 0.220313 -
1.77377 0.00597096 preview
2.73592 0.00176747 -
3.45404 0.00139623 -
4.19018 0.00124441 -
4.87832 0.000937513 -
7.7762 0.00073071 -
EOD
$presets8 << EOD
1.77377 0.00597096 preview
3.50788 0.00141728 final
EOD
set terminal pngcairo size 1280,2400 font ',11'
set output '/work/main/bench/results/error_vs_time.png'
set logscale xy
set format x '%g'
set format y '%g'
set xtics (0.01, 0.02, 0.05, 0.1, 0.2, 0.5, 1, 2, 5, 10, 20, 50, 100, 200, 500, 1000, 2000, 5000)
set xlabel 'time (s)'
set ylabel 'relMSE'
set grid xtics ytics mxtics mytics
set key top right box opaque font ',9'
set datafile missing 'nan'
set multiplot layout 5,2 title 'error against time (medians; circled: Pareto frontier)'
set title 'cornell-box'
set xrange [0.181638:19.8094]
set yrange [0.000650153:14.3219]
plot $path0 using 1:2 with linespoints lw 2 pt 7 ps 0.8 lc rgb '#1f77b4' title 'path', \
     $pm0 using 1:2 with points pt 9 ps 1.0 lc rgb '#d62728' title 'photon-map (sweep)', \
     $pmcurve0 using 1:2 with lines lw 2 lc rgb '#d62728' title 'photon-map (best)', \
     $front0 using 1:2 with points pt 6 ps 2.2 lw 1.5 lc rgb 'black' title 'Pareto frontier', \
     $presets0 using 1:2:3 with labels offset char 1.2,0.8 left font ',10' notitle
set title 'cornell-box-diffuse'
set xrange [0.117867:15.3606]
set yrange [0.000417837:0.907045]
plot $path1 using 1:2 with linespoints lw 2 pt 7 ps 0.8 lc rgb '#1f77b4' title 'path', \
     $pm1 using 1:2 with points pt 9 ps 1.0 lc rgb '#d62728' title 'photon-map (sweep)', \
     $pmcurve1 using 1:2 with lines lw 2 lc rgb '#d62728' title 'photon-map (best)', \
     $front1 using 1:2 with points pt 6 ps 2.2 lw 1.5 lc rgb 'black' title 'Pareto frontier', \
     $presets1 using 1:2:3 with labels offset char 1.2,0.8 left font ',10' notitle
set title 'caustic-area'
set xrange [0.0591781:20.8854]
set yrange [0.0150937:29.7932]
plot $path2 using 1:2 with linespoints lw 2 pt 7 ps 0.8 lc rgb '#1f77b4' title 'path', \
     $pm2 using 1:2 with points pt 9 ps 1.0 lc rgb '#d62728' title 'photon-map (sweep)', \
     $pmcurve2 using 1:2 with lines lw 2 lc rgb '#d62728' title 'photon-map (best)', \
     $front2 using 1:2 with points pt 6 ps 2.2 lw 1.5 lc rgb 'black' title 'Pareto frontier', \
     $presets2 using 1:2:3 with labels offset char 1.2,0.8 left font ',10' notitle
set title 'spheres-room'
set xrange [0.262049:27.4136]
set yrange [0.000755791:0.45809]
plot $path3 using 1:2 with linespoints lw 2 pt 7 ps 0.8 lc rgb '#1f77b4' title 'path', \
     $pm3 using 1:2 with points pt 9 ps 1.0 lc rgb '#d62728' title 'photon-map (sweep)', \
     $pmcurve3 using 1:2 with lines lw 2 lc rgb '#d62728' title 'photon-map (best)', \
     $front3 using 1:2 with points pt 6 ps 2.2 lw 1.5 lc rgb 'black' title 'Pareto frontier', \
     $presets3 using 1:2:3 with labels offset char 1.2,0.8 left font ',10' notitle
set title 'sunlit-room'
set xrange [0.237632:27.375]
set yrange [0.00102172:3.62424]
plot $path4 using 1:2 with linespoints lw 2 pt 7 ps 0.8 lc rgb '#1f77b4' title 'path', \
     $pm4 using 1:2 with points pt 9 ps 1.0 lc rgb '#d62728' title 'photon-map (sweep)', \
     $pmcurve4 using 1:2 with lines lw 2 lc rgb '#d62728' title 'photon-map (best)', \
     $front4 using 1:2 with points pt 6 ps 2.2 lw 1.5 lc rgb 'black' title 'Pareto frontier', \
     $presets4 using 1:2:3 with labels offset char 1.2,0.8 left font ',10' notitle
set title 'foggy-room'
set xrange [0.543244:72.2391]
set yrange [0.000736425:0.998514]
plot $path5 using 1:2 with linespoints lw 2 pt 7 ps 0.8 lc rgb '#1f77b4' title 'path', \
     $pm5 using 1:2 with points pt 9 ps 1.0 lc rgb '#d62728' title 'photon-map (sweep)', \
     $pmcurve5 using 1:2 with lines lw 2 lc rgb '#d62728' title 'photon-map (best)', \
     $front5 using 1:2 with points pt 6 ps 2.2 lw 1.5 lc rgb 'black' title 'Pareto frontier', \
     $presets5 using 1:2:3 with labels offset char 1.2,0.8 left font ',10' notitle
set title 'glossy-objects'
set xrange [0.258971:23.6482]
set yrange [0.00127975:1.79992]
plot $path6 using 1:2 with linespoints lw 2 pt 7 ps 0.8 lc rgb '#1f77b4' title 'path', \
     $pm6 using 1:2 with points pt 9 ps 1.0 lc rgb '#d62728' title 'photon-map (sweep)', \
     $pmcurve6 using 1:2 with lines lw 2 lc rgb '#d62728' title 'photon-map (best)', \
     $front6 using 1:2 with points pt 6 ps 2.2 lw 1.5 lc rgb 'black' title 'Pareto frontier', \
     $presets6 using 1:2:3 with labels offset char 1.2,0.8 left font ',10' notitle
set title 'cornell-box-512'
set xrange [0.578438:26.948]
set yrange [0.00138781:14.698]
plot $path7 using 1:2 with linespoints lw 2 pt 7 ps 0.8 lc rgb '#1f77b4' title 'path', \
     $pm7 using 1:2 with points pt 9 ps 1.0 lc rgb '#d62728' title 'photon-map (sweep)', \
     $pmcurve7 using 1:2 with lines lw 2 lc rgb '#d62728' title 'photon-map (best)', \
     $front7 using 1:2 with points pt 6 ps 2.2 lw 1.5 lc rgb 'black' title 'Pareto frontier', \
     $presets7 using 1:2:3 with labels offset char 1.2,0.8 left font ',10' notitle
set title 'cornell-box-diffuse-512'
set xrange [0.406891:15.365]
set yrange [0.000365355:0.881251]
plot $path8 using 1:2 with linespoints lw 2 pt 7 ps 0.8 lc rgb '#1f77b4' title 'path', \
     $pm8 using 1:2 with points pt 9 ps 1.0 lc rgb '#d62728' title 'photon-map (sweep)', \
     $pmcurve8 using 1:2 with lines lw 2 lc rgb '#d62728' title 'photon-map (best)', \
     $front8 using 1:2 with points pt 6 ps 2.2 lw 1.5 lc rgb 'black' title 'Pareto frontier', \
     $presets8 using 1:2:3 with labels offset char 1.2,0.8 left font ',10' notitle
unset multiplot
