$path0 << EOD
0.228375 3.58047 -
0.834825 0.843455 -
3.43304 0.210066 -
12.2067 0.0552577 -
EOD
$pm0 << EOD
0.876958 0.00746199 preview
2.7396 0.00217748 final
2.11295 0.00375927 -
1.78211 0.00421091 -
5.47046 0.00169185 -
2.33039 0.00270385 -
3.35146 0.0020596 -
2.84067 0.00210669 -
2.20715 0.00236828 -
4.06586 0.00181497 -
6.86427 0.0015042 -
EOD
$pmcurve0 << EOD
0.876958 0.00746199 preview
1.78211 0.00421091 -
2.11295 0.00375927 -
2.20715 0.00236828 -
2.7396 0.00217748 final
2.84067 0.00210669 -
3.35146 0.0020596 -
4.06586 0.00181497 -
5.47046 0.00169185 -
6.86427 0.0015042 -
EOD
$front0 << EOD
0.228375 3.58047 -
0.834825 0.843455 -
0.876958 0.00746199 preview
1.78211 0.00421091 -
2.11295 0.00375927 -
2.20715 0.00236828 -
2.7396 0.00217748 final
2.84067 0.00210669 -
3.35146 0.0020596 -
4.06586 0.00181497 -
5.47046 0.00169185 -
6.86427 0.0015042 -
EOD
$presets0 << EOD
0.876958 0.00746199 preview
2.7396 0.00217748 final
EOD
$path1 << EOD
0.155168 0.226761 -
0.608489 0.0488014 -
2.42764 0.0107455 -
9.67644 0.00262324 -
EOD
$pm1 << EOD
0.515627 0.00684019 preview
1.30133 0.00155081 final
1.10361 0.00272316 -
1.04615 0.00257572 -
2.30871 0.00144072 -
1.01873 0.00185453 -
1.82547 0.00144731 -
1.68361 0.0014927 -
0.954638 0.00180995 -
1.67021 0.00112296 -
2.5213 0.000922323 -
EOD
$pmcurve1 << EOD
0.515627 0.00684019 preview
0.954638 0.00180995 -
1.30133 0.00155081 final
1.67021 0.00112296 -
2.5213 0.000922323 -
EOD
$front1 << EOD
0.155168 0.226761 -
0.515627 0.00684019 preview
0.954638 0.00180995 -
1.30133 0.00155081 final
1.67021 0.00112296 -
2.5213 0.000922323 -
EOD
$presets1 << EOD
0.515627 0.00684019 preview
1.30133 0.00155081 final
EOD
$path2 << EOD
0.0696155 7.44762 -
0.239376 2.70592 -
0.937649 0.842902 -
3.61602 0.111126 -
15.2825 0.0386079 -
EOD
$pm2 << EOD
0.301284 0.0371792 preview
0.704892 0.0268083 final
0.629083 0.0268657 -
0.383498 0.148531 -
2.153 0.0153789 -
0.676535 0.0434915 -
0.721173 0.0290299 -
0.673949 0.0325113 -
0.667085 0.0323995 -
0.867289 0.0252793 -
1.18302 0.0301577 -
EOD
$pmcurve2 << EOD
0.301284 0.0371792 preview
0.629083 0.0268657 -
0.704892 0.0268083 final
0.867289 0.0252793 -
2.153 0.0153789 -
EOD
$front2 << EOD
0.0696155 7.44762 -
0.239376 2.70592 -
0.301284 0.0371792 preview
0.629083 0.0268657 -
0.704892 0.0268083 final
0.867289 0.0252793 -
2.153 0.0153789 -
EOD
$presets2 << EOD
0.301284 0.0371792 preview
0.704892 0.0268083 final
EOD
$path3 << EOD
0.288142 0.114524 -
1.01493 0.0260227 -
3.84346 0.00616214 -
16.5449 0.00151146 -
EOD
$pm3 << EOD
0.872043 0.0164399 preview
1.86226 0.00362369 final
1.48505 0.00533692 -
1.72068 0.00964569 -
2.77273 0.0018709 -
1.45942 0.00371197 -
2.44635 0.00347779 -
2.25804 0.00365153 -
1.40679 0.00370848 -
2.13951 0.00293941 -
3.39667 0.00263026 -
EOD
$pmcurve3 << EOD
0.872043 0.0164399 preview
1.40679 0.00370848 -
1.86226 0.00362369 final
2.13951 0.00293941 -
2.77273 0.0018709 -
EOD
$front3 << EOD
0.288142 0.114524 -
0.872043 0.0164399 preview
1.40679 0.00370848 -
1.86226 0.00362369 final
2.13951 0.00293941 -
2.77273 0.0018709 -
16.5449 0.00151146 -
EOD
$presets3 << EOD
0.872043 0.0164399 preview
1.86226 0.00362369 final
EOD
set terminal pngcairo size 1280,960 font ',11'
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
set multiplot layout 2,2 title 'error against time (medians; circled: Pareto frontier)'
set title 'cornell-box'
set xrange [0.15225:18.31]
set yrange [0.000752102:14.3219]
plot $path0 using 1:2 with linespoints lw 2 pt 7 ps 0.8 lc rgb '#1f77b4' title 'path', \
     $pm0 using 1:2 with points pt 9 ps 1.0 lc rgb '#d62728' title 'photon-map (sweep)', \
     $pmcurve0 using 1:2 with lines lw 2 lc rgb '#d62728' title 'photon-map (best)', \
     $front0 using 1:2 with points pt 6 ps 2.2 lw 1.5 lc rgb 'black' title 'Pareto frontier', \
     $presets0 using 1:2:3 with labels offset char 1.2,0.8 left font ',10' notitle
set title 'cornell-box-diffuse'
set xrange [0.103445:14.5147]
set yrange [0.000461162:0.907045]
plot $path1 using 1:2 with linespoints lw 2 pt 7 ps 0.8 lc rgb '#1f77b4' title 'path', \
     $pm1 using 1:2 with points pt 9 ps 1.0 lc rgb '#d62728' title 'photon-map (sweep)', \
     $pmcurve1 using 1:2 with lines lw 2 lc rgb '#d62728' title 'photon-map (best)', \
     $front1 using 1:2 with points pt 6 ps 2.2 lw 1.5 lc rgb 'black' title 'Pareto frontier', \
     $presets1 using 1:2:3 with labels offset char 1.2,0.8 left font ',10' notitle
set title 'caustic-area'
set xrange [0.0464103:22.9237]
set yrange [0.00768945:29.7905]
plot $path2 using 1:2 with linespoints lw 2 pt 7 ps 0.8 lc rgb '#1f77b4' title 'path', \
     $pm2 using 1:2 with points pt 9 ps 1.0 lc rgb '#d62728' title 'photon-map (sweep)', \
     $pmcurve2 using 1:2 with lines lw 2 lc rgb '#d62728' title 'photon-map (best)', \
     $front2 using 1:2 with points pt 6 ps 2.2 lw 1.5 lc rgb 'black' title 'Pareto frontier', \
     $presets2 using 1:2:3 with labels offset char 1.2,0.8 left font ',10' notitle
set title 'spheres-room'
set xrange [0.192095:24.8174]
set yrange [0.000755729:0.458097]
plot $path3 using 1:2 with linespoints lw 2 pt 7 ps 0.8 lc rgb '#1f77b4' title 'path', \
     $pm3 using 1:2 with points pt 9 ps 1.0 lc rgb '#d62728' title 'photon-map (sweep)', \
     $pmcurve3 using 1:2 with lines lw 2 lc rgb '#d62728' title 'photon-map (best)', \
     $front3 using 1:2 with points pt 6 ps 2.2 lw 1.5 lc rgb 'black' title 'Pareto frontier', \
     $presets3 using 1:2:3 with labels offset char 1.2,0.8 left font ',10' notitle
unset multiplot
