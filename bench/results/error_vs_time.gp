$path0 << EOD
0.231199 3.58048 -
0.826577 0.843455 -
3.2587 0.210066 -
12.5826 0.055256 -
EOD
$pm0 << EOD
0.644614 0.00740642 preview
1.69651 0.00210898 final
1.3711 0.00392271 -
1.37904 0.00414681 -
2.71312 0.00159452 -
1.46358 0.00231877 -
2.6411 0.0019582 -
1.86729 0.00205172 -
1.41734 0.00227059 -
2.40861 0.00157509 -
3.73511 0.0013042 -
EOD
$pmcurve0 << EOD
0.644614 0.00740642 preview
1.3711 0.00392271 -
1.41734 0.00227059 -
1.69651 0.00210898 final
1.86729 0.00205172 -
2.40861 0.00157509 -
3.73511 0.0013042 -
EOD
$front0 << EOD
0.231199 3.58048 -
0.644614 0.00740642 preview
1.3711 0.00392271 -
1.41734 0.00227059 -
1.69651 0.00210898 final
1.86729 0.00205172 -
2.40861 0.00157509 -
3.73511 0.0013042 -
EOD
$presets0 << EOD
0.644614 0.00740642 preview
1.69651 0.00210898 final
EOD
$path1 << EOD
0.169701 0.226761 -
0.643914 0.0488014 -
2.53702 0.0107455 -
10.1157 0.00262325 -
EOD
$pm1 << EOD
0.4541 0.00596947 preview
1.14355 0.00153373 final
0.929319 0.0026902 -
1.00349 0.00190423 -
1.56632 0.00138981 -
0.873648 0.00187397 -
1.5941 0.00143214 -
1.37511 0.00147867 -
0.870874 0.00179461 -
1.536 0.0010644 -
2.42048 0.00083496 -
EOD
$pmcurve1 << EOD
0.4541 0.00596947 preview
0.870874 0.00179461 -
1.14355 0.00153373 final
1.37511 0.00147867 -
1.536 0.0010644 -
2.42048 0.00083496 -
EOD
$front1 << EOD
0.169701 0.226761 -
0.4541 0.00596947 preview
0.870874 0.00179461 -
1.14355 0.00153373 final
1.37511 0.00147867 -
1.536 0.0010644 -
2.42048 0.00083496 -
EOD
$presets1 << EOD
0.4541 0.00596947 preview
1.14355 0.00153373 final
EOD
$path2 << EOD
0.0749994 7.44829 -
0.256483 2.70614 -
1.01119 0.842645 -
4.00097 0.111139 -
15.0367 0.0386054 -
EOD
$pm2 << EOD
0.12074 0.0483574 preview
0.306643 0.0353359 final
0.278441 0.0347963 -
0.127301 0.07296 -
0.982558 0.0470709 -
0.297709 0.0366154 -
0.29881 0.032709 -
0.296332 0.0353359 -
0.295308 0.0353359 -
0.337701 0.0319263 -
0.408156 0.0323748 -
EOD
$pmcurve2 << EOD
0.12074 0.0483574 preview
0.278441 0.0347963 -
0.29881 0.032709 -
0.337701 0.0319263 -
EOD
$front2 << EOD
0.0749994 7.44829 -
0.12074 0.0483574 preview
0.278441 0.0347963 -
0.29881 0.032709 -
0.337701 0.0319263 -
EOD
$presets2 << EOD
0.12074 0.0483574 preview
0.306643 0.0353359 final
EOD
$path3 << EOD
0.291549 0.114523 -
1.02325 0.0260191 -
3.90379 0.00616203 -
15.757 0.00151158 -
EOD
$pm3 << EOD
0.845087 0.0139629 preview
1.45214 0.0036056 final
1.26205 0.00533908 -
1.64788 0.00716777 -
1.94657 0.00191428 -
1.11684 0.00378104 -
2.22085 0.00347778 -
1.86036 0.00363279 -
1.22793 0.00368592 -
1.90307 0.00291094 -
2.7715 0.00260588 -
EOD
$pmcurve3 << EOD
0.845087 0.0139629 preview
1.11684 0.00378104 -
1.22793 0.00368592 -
1.45214 0.0036056 final
1.90307 0.00291094 -
1.94657 0.00191428 -
EOD
$front3 << EOD
0.291549 0.114523 -
0.845087 0.0139629 preview
1.11684 0.00378104 -
1.22793 0.00368592 -
1.45214 0.0036056 final
1.90307 0.00291094 -
1.94657 0.00191428 -
15.757 0.00151158 -
EOD
$presets3 << EOD
0.845087 0.0139629 preview
1.45214 0.0036056 final
EOD
$path4 << EOD
0.288189 0.90606 -
1.10487 0.216089 -
4.29666 0.052179 -
17.2655 0.0131238 -
EOD
$pm4 << EOD
0.910828 0.00579784 preview
2.17334 0.00233236 final
1.90687 0.00291438 -
1.90205 0.00266964 -
2.85422 0.002136 -
1.45651 0.00289744 -
3.31742 0.00193386 -
2.60726 0.00222572 -
1.5346 0.00257833 -
2.76429 0.00211389 -
3.78531 0.00201185 -
EOD
$pmcurve4 << EOD
0.910828 0.00579784 preview
1.45651 0.00289744 -
1.5346 0.00257833 -
2.17334 0.00233236 final
2.60726 0.00222572 -
2.76429 0.00211389 -
3.31742 0.00193386 -
EOD
$front4 << EOD
0.288189 0.90606 -
0.910828 0.00579784 preview
1.45651 0.00289744 -
1.5346 0.00257833 -
2.17334 0.00233236 final
2.60726 0.00222572 -
2.76429 0.00211389 -
3.31742 0.00193386 -
EOD
$presets4 << EOD
0.910828 0.00579784 preview
2.17334 0.00233236 final
EOD
$path5 << EOD
0.78059 0.249629 -
3.1142 0.0462991 -
12.3811 0.0189438 -
49.1393 0.00506844 -
EOD
$pm5 << EOD
2.38599 0.00299958 preview
8.75642 0.00181443 final
6.1371 0.00193366 -
8.98578 0.00190706 -
9.00906 0.00170313 -
7.29555 0.00233119 -
11.7014 0.00147078 -
10.0969 0.00157614 -
7.84705 0.00191493 -
14.0555 0.00176282 -
24.5965 0.0017397 -
EOD
$pmcurve5 << EOD
2.38599 0.00299958 preview
6.1371 0.00193366 -
7.84705 0.00191493 -
8.75642 0.00181443 final
9.00906 0.00170313 -
10.0969 0.00157614 -
11.7014 0.00147078 -
EOD
$front5 << EOD
0.78059 0.249629 -
2.38599 0.00299958 preview
6.1371 0.00193366 -
7.84705 0.00191493 -
8.75642 0.00181443 final
9.00906 0.00170313 -
10.0969 0.00157614 -
11.7014 0.00147078 -
EOD
$presets5 << EOD
2.38599 0.00299958 preview
8.75642 0.00181443 final
EOD
$path6 << EOD
0.349231 0.449979 -
1.15938 0.120524 -
4.37384 0.0302586 -
17.4092 0.00737265 -
EOD
$pm6 << EOD
0.821594 0.0305577 preview
2.17183 0.00722381 final
1.68784 0.0123664 -
1.85783 0.00825198 -
3.39698 0.00681227 -
1.80635 0.00731299 -
2.96053 0.00718908 -
2.31044 0.00721519 -
1.76377 0.0072545 -
3.04993 0.00424049 -
4.91305 0.00253558 -
EOD
$pmcurve6 << EOD
0.821594 0.0305577 preview
1.68784 0.0123664 -
1.76377 0.0072545 -
2.17183 0.00722381 final
2.31044 0.00721519 -
2.96053 0.00718908 -
3.04993 0.00424049 -
4.91305 0.00253558 -
EOD
$front6 << EOD
0.349231 0.449979 -
0.821594 0.0305577 preview
1.68784 0.0123664 -
1.76377 0.0072545 -
2.17183 0.00722381 final
2.31044 0.00721519 -
2.96053 0.00718908 -
3.04993 0.00424049 -
4.91305 0.00253558 -
EOD
$presets6 << EOD
0.821594 0.0305577 preview
2.17183 0.00722381 final
EOD
$path7 << EOD
0.828335 3.67449 -
3.21503 0.911427 -
12.4552 0.224384 -
EOD
$pm7 << EOD
2.01921 0.00799414 preview
4.54826 0.00340039 final
3.31615 0.00427326 -
3.81132 0.00575842 -
6.56025 0.00281095 -
3.73434 0.00374174 -
5.94354 0.00325187 -
5.09183 0.00335128 -
4.49658 0.00336922 -
6.88509 0.00308045 -
11.709 0.0029151 -
EOD
$pmcurve7 << EOD
2.01921 0.00799414 preview
3.31615 0.00427326 -
3.73434 0.00374174 -
4.49658 0.00336922 -
5.09183 0.00335128 -
5.94354 0.00325187 -
6.56025 0.00281095 -
EOD
$front7 << EOD
0.828335 3.67449 -
2.01921 0.00799414 preview
3.31615 0.00427326 -
3.73434 0.00374174 -
4.49658 0.00336922 -
5.09183 0.00335128 -
5.94354 0.00325187 -
6.56025 0.00281095 -
EOD
$presets7 << EOD
2.01921 0.00799414 preview
4.54826 0.00340039 final
EOD
$path8 << EOD
0.648098 0.220313 -
2.52892 0.0486853 -
10.0149 0.0106704 -
EOD
$pm8 << EOD
1.38396 0.00597587 preview
2.8687 0.00141719 final
2.1462 0.00241339 -
2.68541 0.00183713 -
3.29619 0.00124524 -
2.30557 0.00176676 -
3.93896 0.00129747 -
3.51491 0.00139104 -
2.93509 0.00139551 -
4.21496 0.000937445 -
6.96213 0.000730663 -
EOD
$pmcurve8 << EOD
1.38396 0.00597587 preview
2.1462 0.00241339 -
2.30557 0.00176676 -
2.8687 0.00141719 final
2.93509 0.00139551 -
3.29619 0.00124524 -
4.21496 0.000937445 -
6.96213 0.000730663 -
EOD
$front8 << EOD
0.648098 0.220313 -
1.38396 0.00597587 preview
2.1462 0.00241339 -
2.30557 0.00176676 -
2.8687 0.00141719 final
2.93509 0.00139551 -
3.29619 0.00124524 -
4.21496 0.000937445 -
6.96213 0.000730663 -
EOD
$presets8 << EOD
1.38396 0.00597587 preview
2.8687 0.00141719 final
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
set xrange [0.154133:18.8739]
set yrange [0.000652101:14.3219]
plot $path0 using 1:2 with linespoints lw 2 pt 7 ps 0.8 lc rgb '#1f77b4' title 'path', \
     $pm0 using 1:2 with points pt 9 ps 1.0 lc rgb '#d62728' title 'photon-map (sweep)', \
     $pmcurve0 using 1:2 with lines lw 2 lc rgb '#d62728' title 'photon-map (best)', \
     $front0 using 1:2 with points pt 6 ps 2.2 lw 1.5 lc rgb 'black' title 'Pareto frontier', \
     $presets0 using 1:2:3 with labels offset char 1.2,0.8 left font ',10' notitle
set title 'cornell-box-diffuse'
set xrange [0.113134:15.1735]
set yrange [0.00041748:0.907045]
plot $path1 using 1:2 with linespoints lw 2 pt 7 ps 0.8 lc rgb '#1f77b4' title 'path', \
     $pm1 using 1:2 with points pt 9 ps 1.0 lc rgb '#d62728' title 'photon-map (sweep)', \
     $pmcurve1 using 1:2 with lines lw 2 lc rgb '#d62728' title 'photon-map (best)', \
     $front1 using 1:2 with points pt 6 ps 2.2 lw 1.5 lc rgb 'black' title 'Pareto frontier', \
     $presets1 using 1:2:3 with labels offset char 1.2,0.8 left font ',10' notitle
set title 'caustic-area'
set xrange [0.0499996:22.5551]
set yrange [0.0159632:29.7932]
plot $path2 using 1:2 with linespoints lw 2 pt 7 ps 0.8 lc rgb '#1f77b4' title 'path', \
     $pm2 using 1:2 with points pt 9 ps 1.0 lc rgb '#d62728' title 'photon-map (sweep)', \
     $pmcurve2 using 1:2 with lines lw 2 lc rgb '#d62728' title 'photon-map (best)', \
     $front2 using 1:2 with points pt 6 ps 2.2 lw 1.5 lc rgb 'black' title 'Pareto frontier', \
     $presets2 using 1:2:3 with labels offset char 1.2,0.8 left font ',10' notitle
set title 'spheres-room'
set xrange [0.194366:23.6356]
set yrange [0.000755791:0.45809]
plot $path3 using 1:2 with linespoints lw 2 pt 7 ps 0.8 lc rgb '#1f77b4' title 'path', \
     $pm3 using 1:2 with points pt 9 ps 1.0 lc rgb '#d62728' title 'photon-map (sweep)', \
     $pmcurve3 using 1:2 with lines lw 2 lc rgb '#d62728' title 'photon-map (best)', \
     $front3 using 1:2 with points pt 6 ps 2.2 lw 1.5 lc rgb 'black' title 'Pareto frontier', \
     $presets3 using 1:2:3 with labels offset char 1.2,0.8 left font ',10' notitle
set title 'sunlit-room'
set xrange [0.192126:25.8983]
set yrange [0.00096693:3.62424]
plot $path4 using 1:2 with linespoints lw 2 pt 7 ps 0.8 lc rgb '#1f77b4' title 'path', \
     $pm4 using 1:2 with points pt 9 ps 1.0 lc rgb '#d62728' title 'photon-map (sweep)', \
     $pmcurve4 using 1:2 with lines lw 2 lc rgb '#d62728' title 'photon-map (best)', \
     $front4 using 1:2 with points pt 6 ps 2.2 lw 1.5 lc rgb 'black' title 'Pareto frontier', \
     $presets4 using 1:2:3 with labels offset char 1.2,0.8 left font ',10' notitle
set title 'foggy-room'
set xrange [0.520393:73.7089]
set yrange [0.00073539:0.998514]
plot $path5 using 1:2 with linespoints lw 2 pt 7 ps 0.8 lc rgb '#1f77b4' title 'path', \
     $pm5 using 1:2 with points pt 9 ps 1.0 lc rgb '#d62728' title 'photon-map (sweep)', \
     $pmcurve5 using 1:2 with lines lw 2 lc rgb '#d62728' title 'photon-map (best)', \
     $front5 using 1:2 with points pt 6 ps 2.2 lw 1.5 lc rgb 'black' title 'Pareto frontier', \
     $presets5 using 1:2:3 with labels offset char 1.2,0.8 left font ',10' notitle
set title 'glossy-objects'
set xrange [0.23282:26.1138]
set yrange [0.00126779:1.79992]
plot $path6 using 1:2 with linespoints lw 2 pt 7 ps 0.8 lc rgb '#1f77b4' title 'path', \
     $pm6 using 1:2 with points pt 9 ps 1.0 lc rgb '#d62728' title 'photon-map (sweep)', \
     $pmcurve6 using 1:2 with lines lw 2 lc rgb '#d62728' title 'photon-map (best)', \
     $front6 using 1:2 with points pt 6 ps 2.2 lw 1.5 lc rgb 'black' title 'Pareto frontier', \
     $presets6 using 1:2:3 with labels offset char 1.2,0.8 left font ',10' notitle
set title 'cornell-box-512'
set xrange [0.552223:18.6828]
set yrange [0.00140548:14.698]
plot $path7 using 1:2 with linespoints lw 2 pt 7 ps 0.8 lc rgb '#1f77b4' title 'path', \
     $pm7 using 1:2 with points pt 9 ps 1.0 lc rgb '#d62728' title 'photon-map (sweep)', \
     $pmcurve7 using 1:2 with lines lw 2 lc rgb '#d62728' title 'photon-map (best)', \
     $front7 using 1:2 with points pt 6 ps 2.2 lw 1.5 lc rgb 'black' title 'Pareto frontier', \
     $presets7 using 1:2:3 with labels offset char 1.2,0.8 left font ',10' notitle
set title 'cornell-box-diffuse-512'
set xrange [0.432066:15.0223]
set yrange [0.000365332:0.881251]
plot $path8 using 1:2 with linespoints lw 2 pt 7 ps 0.8 lc rgb '#1f77b4' title 'path', \
     $pm8 using 1:2 with points pt 9 ps 1.0 lc rgb '#d62728' title 'photon-map (sweep)', \
     $pmcurve8 using 1:2 with lines lw 2 lc rgb '#d62728' title 'photon-map (best)', \
     $front8 using 1:2 with points pt 6 ps 2.2 lw 1.5 lc rgb 'black' title 'Pareto frontier', \
     $presets8 using 1:2:3 with labels offset char 1.2,0.8 left font ',10' notitle
unset multiplot
