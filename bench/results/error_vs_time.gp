$path0 << EOD
0.213489 3.58047 -
0.766986 0.843455 -
3.0166 0.210066 -
12.009 0.0552577 -
EOD
$pm0 << EOD
0.748794 0.00746199 preview
2.33927 0.00217748 final
1.70552 0.00375927 -
1.53594 0.00421091 -
5.00216 0.00169185 -
1.95096 0.00270385 -
3.00921 0.0020596 -
2.56923 0.00210669 -
1.96731 0.00236828 -
3.55373 0.00181497 -
5.77584 0.0015042 -
EOD
$pmcurve0 << EOD
0.748794 0.00746199 preview
1.53594 0.00421091 -
1.70552 0.00375927 -
1.95096 0.00270385 -
1.96731 0.00236828 -
2.33927 0.00217748 final
2.56923 0.00210669 -
3.00921 0.0020596 -
3.55373 0.00181497 -
5.00216 0.00169185 -
5.77584 0.0015042 -
EOD
$front0 << EOD
0.213489 3.58047 -
0.748794 0.00746199 preview
1.53594 0.00421091 -
1.70552 0.00375927 -
1.95096 0.00270385 -
1.96731 0.00236828 -
2.33927 0.00217748 final
2.56923 0.00210669 -
3.00921 0.0020596 -
3.55373 0.00181497 -
5.00216 0.00169185 -
5.77584 0.0015042 -
EOD
$presets0 << EOD
0.748794 0.00746199 preview
2.33927 0.00217748 final
EOD
$path1 << EOD
0.152754 0.226761 -
0.590279 0.0488014 -
2.32826 0.0107455 -
9.17736 0.00262324 -
EOD
$pm1 << EOD
0.500458 0.00684019 preview
1.35687 0.00155081 final
1.10964 0.00272316 -
1.03396 0.00257572 -
2.27823 0.00144072 -
1.01942 0.00185453 -
1.81438 0.00144731 -
1.62248 0.0014927 -
0.933169 0.00180995 -
1.65794 0.00112296 -
2.3156 0.000922323 -
EOD
$pmcurve1 << EOD
0.500458 0.00684019 preview
0.933169 0.00180995 -
1.35687 0.00155081 final
1.62248 0.0014927 -
1.65794 0.00112296 -
2.3156 0.000922323 -
EOD
$front1 << EOD
0.152754 0.226761 -
0.500458 0.00684019 preview
0.933169 0.00180995 -
1.35687 0.00155081 final
1.62248 0.0014927 -
1.65794 0.00112296 -
2.3156 0.000922323 -
EOD
$presets1 << EOD
0.500458 0.00684019 preview
1.35687 0.00155081 final
EOD
$path2 << EOD
0.0718502 7.44762 -
0.23892 2.70592 -
0.91831 0.842902 -
3.51804 0.111126 -
14.4186 0.0386079 -
EOD
$pm2 << EOD
0.189424 0.0371792 preview
0.553566 0.0268083 final
0.469013 0.0268657 -
0.317228 0.148531 -
1.60769 0.0153789 -
0.510097 0.0434915 -
0.554302 0.0290299 -
0.510726 0.0325113 -
0.518073 0.0323995 -
0.700792 0.0252793 -
1.01421 0.0301577 -
EOD
$pmcurve2 << EOD
0.189424 0.0371792 preview
0.469013 0.0268657 -
0.553566 0.0268083 final
0.700792 0.0252793 -
1.60769 0.0153789 -
EOD
$front2 << EOD
0.0718502 7.44762 -
0.189424 0.0371792 preview
0.469013 0.0268657 -
0.553566 0.0268083 final
0.700792 0.0252793 -
1.60769 0.0153789 -
EOD
$presets2 << EOD
0.189424 0.0371792 preview
0.553566 0.0268083 final
EOD
$path3 << EOD
0.285631 0.114524 -
0.991856 0.0260227 -
3.74446 0.00616214 -
14.9558 0.00151146 -
EOD
$pm3 << EOD
0.81512 0.0164399 preview
1.64581 0.00362369 final
1.41332 0.00533692 -
1.61342 0.00964569 -
2.47722 0.0018709 -
1.25801 0.00371197 -
2.31362 0.00347779 -
2.14679 0.00365153 -
1.40302 0.00370848 -
2.1112 0.00293941 -
2.94086 0.00263026 -
EOD
$pmcurve3 << EOD
0.81512 0.0164399 preview
1.25801 0.00371197 -
1.40302 0.00370848 -
1.64581 0.00362369 final
2.1112 0.00293941 -
2.47722 0.0018709 -
EOD
$front3 << EOD
0.285631 0.114524 -
0.81512 0.0164399 preview
1.25801 0.00371197 -
1.40302 0.00370848 -
1.64581 0.00362369 final
2.1112 0.00293941 -
2.47722 0.0018709 -
14.9558 0.00151146 -
EOD
$presets3 << EOD
0.81512 0.0164399 preview
1.64581 0.00362369 final
EOD
$path4 << EOD
0.827619 3.67449 -
3.04493 0.911428 -
11.6779 0.224384 -
EOD
$pm4 << EOD
2.33862 0.00843749 preview
6.43474 0.00371822 final
4.27264 0.00459251 -
4.2248 0.00584948 -
13.2225 0.00308299 -
5.68315 0.00404857 -
7.64963 0.00364582 -
7.19885 0.00369224 -
6.44233 0.00370773 -
10.9485 0.00340768 -
19.6225 0.00337033 -
EOD
$pmcurve4 << EOD
2.33862 0.00843749 preview
4.2248 0.00584948 -
4.27264 0.00459251 -
5.68315 0.00404857 -
6.43474 0.00371822 final
6.44233 0.00370773 -
7.19885 0.00369224 -
7.64963 0.00364582 -
10.9485 0.00340768 -
13.2225 0.00308299 -
EOD
$front4 << EOD
0.827619 3.67449 -
2.33862 0.00843749 preview
4.2248 0.00584948 -
4.27264 0.00459251 -
5.68315 0.00404857 -
6.43474 0.00371822 final
6.44233 0.00370773 -
7.19885 0.00369224 -
7.64963 0.00364582 -
10.9485 0.00340768 -
13.2225 0.00308299 -
EOD
$presets4 << EOD
2.33862 0.00843749 preview
6.43474 0.00371822 final
EOD
$path5 << EOD
0.584719 0.220313 -
2.3028 0.0486855 -
9.06632 0.0106705 -
EOD
$pm5 << EOD
1.65947 0.0063875 preview
2.9909 0.00144651 final
2.38831 0.00252052 -
2.83705 0.00253054 -
4.11221 0.00128326 -
2.40005 0.00179583 -
4.11269 0.00134304 -
3.81287 0.00143723 -
3.01125 0.00141689 -
4.19565 0.00103119 -
6.65378 0.000826495 -
EOD
$pmcurve5 << EOD
1.65947 0.0063875 preview
2.38831 0.00252052 -
2.40005 0.00179583 -
2.9909 0.00144651 final
3.01125 0.00141689 -
4.11221 0.00128326 -
4.19565 0.00103119 -
6.65378 0.000826495 -
EOD
$front5 << EOD
0.584719 0.220313 -
1.65947 0.0063875 preview
2.38831 0.00252052 -
2.40005 0.00179583 -
2.9909 0.00144651 final
3.01125 0.00141689 -
4.11221 0.00128326 -
4.19565 0.00103119 -
6.65378 0.000826495 -
EOD
$presets5 << EOD
1.65947 0.0063875 preview
2.9909 0.00144651 final
EOD
set terminal pngcairo size 1280,1440 font ',11'
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
set multiplot layout 3,2 title 'error against time (medians; circled: Pareto frontier)'
set title 'cornell-box'
set xrange [0.142326:18.0134]
set yrange [0.000752102:14.3219]
plot $path0 using 1:2 with linespoints lw 2 pt 7 ps 0.8 lc rgb '#1f77b4' title 'path', \
     $pm0 using 1:2 with points pt 9 ps 1.0 lc rgb '#d62728' title 'photon-map (sweep)', \
     $pmcurve0 using 1:2 with lines lw 2 lc rgb '#d62728' title 'photon-map (best)', \
     $front0 using 1:2 with points pt 6 ps 2.2 lw 1.5 lc rgb 'black' title 'Pareto frontier', \
     $presets0 using 1:2:3 with labels offset char 1.2,0.8 left font ',10' notitle
set title 'cornell-box-diffuse'
set xrange [0.101836:13.766]
set yrange [0.000461162:0.907045]
plot $path1 using 1:2 with linespoints lw 2 pt 7 ps 0.8 lc rgb '#1f77b4' title 'path', \
     $pm1 using 1:2 with points pt 9 ps 1.0 lc rgb '#d62728' title 'photon-map (sweep)', \
     $pmcurve1 using 1:2 with lines lw 2 lc rgb '#d62728' title 'photon-map (best)', \
     $front1 using 1:2 with points pt 6 ps 2.2 lw 1.5 lc rgb 'black' title 'Pareto frontier', \
     $presets1 using 1:2:3 with labels offset char 1.2,0.8 left font ',10' notitle
set title 'caustic-area'
set xrange [0.0479001:21.6279]
set yrange [0.00768945:29.7905]
plot $path2 using 1:2 with linespoints lw 2 pt 7 ps 0.8 lc rgb '#1f77b4' title 'path', \
     $pm2 using 1:2 with points pt 9 ps 1.0 lc rgb '#d62728' title 'photon-map (sweep)', \
     $pmcurve2 using 1:2 with lines lw 2 lc rgb '#d62728' title 'photon-map (best)', \
     $front2 using 1:2 with points pt 6 ps 2.2 lw 1.5 lc rgb 'black' title 'Pareto frontier', \
     $presets2 using 1:2:3 with labels offset char 1.2,0.8 left font ',10' notitle
set title 'spheres-room'
set xrange [0.19042:22.4337]
set yrange [0.000755729:0.458097]
plot $path3 using 1:2 with linespoints lw 2 pt 7 ps 0.8 lc rgb '#1f77b4' title 'path', \
     $pm3 using 1:2 with points pt 9 ps 1.0 lc rgb '#d62728' title 'photon-map (sweep)', \
     $pmcurve3 using 1:2 with lines lw 2 lc rgb '#d62728' title 'photon-map (best)', \
     $front3 using 1:2 with points pt 6 ps 2.2 lw 1.5 lc rgb 'black' title 'Pareto frontier', \
     $presets3 using 1:2:3 with labels offset char 1.2,0.8 left font ',10' notitle
set title 'cornell-box-512'
set xrange [0.551746:29.4338]
set yrange [0.0015415:14.698]
plot $path4 using 1:2 with linespoints lw 2 pt 7 ps 0.8 lc rgb '#1f77b4' title 'path', \
     $pm4 using 1:2 with points pt 9 ps 1.0 lc rgb '#d62728' title 'photon-map (sweep)', \
     $pmcurve4 using 1:2 with lines lw 2 lc rgb '#d62728' title 'photon-map (best)', \
     $front4 using 1:2 with points pt 6 ps 2.2 lw 1.5 lc rgb 'black' title 'Pareto frontier', \
     $presets4 using 1:2:3 with labels offset char 1.2,0.8 left font ',10' notitle
set title 'cornell-box-diffuse-512'
set xrange [0.389813:13.5995]
set yrange [0.000413248:0.881251]
plot $path5 using 1:2 with linespoints lw 2 pt 7 ps 0.8 lc rgb '#1f77b4' title 'path', \
     $pm5 using 1:2 with points pt 9 ps 1.0 lc rgb '#d62728' title 'photon-map (sweep)', \
     $pmcurve5 using 1:2 with lines lw 2 lc rgb '#d62728' title 'photon-map (best)', \
     $front5 using 1:2 with points pt 6 ps 2.2 lw 1.5 lc rgb 'black' title 'Pareto frontier', \
     $presets5 using 1:2:3 with labels offset char 1.2,0.8 left font ',10' notitle
unset multiplot
