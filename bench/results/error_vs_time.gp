$path0 << EOD
0.322287 0.227371 -
1.19465 0.0486818 -
4.64362 0.0109216 -
EOD
$pm0 << EOD
0.885513 0.00671237 preview
3.69966 0.00109101 final
2.51537 0.00269638 -
EOD
$pmcurve0 << EOD
0.885513 0.00671237 preview
2.51537 0.00269638 -
3.69966 0.00109101 final
EOD
$front0 << EOD
0.322287 0.227371 -
0.885513 0.00671237 preview
2.51537 0.00269638 -
3.69966 0.00109101 final
EOD
$presets0 << EOD
0.885513 0.00671237 preview
3.69966 0.00109101 final
EOD
$path1 << EOD
0.0853026 10.4193 -
0.321881 1.87762 -
1.10891 0.566838 -
EOD
$pm1 << EOD
0.56839 0.268788 preview
1.98535 0.014605 final
1.72048 0.0161286 -
EOD
$pmcurve1 << EOD
0.56839 0.268788 preview
1.72048 0.0161286 -
1.98535 0.014605 final
EOD
$front1 << EOD
0.0853026 10.4193 -
0.321881 1.87762 -
0.56839 0.268788 preview
1.72048 0.0161286 -
1.98535 0.014605 final
EOD
$presets1 << EOD
0.56839 0.268788 preview
1.98535 0.014605 final
EOD
$path2 << EOD
0.531777 0.115858 -
1.94566 0.0259198 -
7.45636 0.00616467 -
EOD
$pm2 << EOD
1.47188 0.0164917 preview
4.47658 0.00298969 final
3.13542 0.00544427 -
EOD
$pmcurve2 << EOD
1.47188 0.0164917 preview
3.13542 0.00544427 -
4.47658 0.00298969 final
EOD
$front2 << EOD
0.531777 0.115858 -
1.47188 0.0164917 preview
3.13542 0.00544427 -
4.47658 0.00298969 final
EOD
$presets2 << EOD
1.47188 0.0164917 preview
4.47658 0.00298969 final
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
set title 'cornell-box-diffuse'
set xrange [0.214858:6.96542]
set yrange [0.000545504:0.909484]
plot $path0 using 1:2 with linespoints lw 2 pt 7 ps 0.8 lc rgb '#1f77b4' title 'path', \
     $pm0 using 1:2 with points pt 9 ps 1.0 lc rgb '#d62728' title 'photon-map (sweep)', \
     $pmcurve0 using 1:2 with lines lw 2 lc rgb '#d62728' title 'photon-map (best)', \
     $front0 using 1:2 with points pt 6 ps 2.2 lw 1.5 lc rgb 'black' title 'Pareto frontier', \
     $presets0 using 1:2:3 with labels offset char 1.2,0.8 left font ',10' notitle
set title 'caustic-area'
set xrange [0.0568684:2.97802]
set yrange [0.00730252:41.6772]
plot $path1 using 1:2 with linespoints lw 2 pt 7 ps 0.8 lc rgb '#1f77b4' title 'path', \
     $pm1 using 1:2 with points pt 9 ps 1.0 lc rgb '#d62728' title 'photon-map (sweep)', \
     $pmcurve1 using 1:2 with lines lw 2 lc rgb '#d62728' title 'photon-map (best)', \
     $front1 using 1:2 with points pt 6 ps 2.2 lw 1.5 lc rgb 'black' title 'Pareto frontier', \
     $presets1 using 1:2:3 with labels offset char 1.2,0.8 left font ',10' notitle
set title 'spheres-room'
set xrange [0.354518:11.1845]
set yrange [0.00149485:0.463432]
plot $path2 using 1:2 with linespoints lw 2 pt 7 ps 0.8 lc rgb '#1f77b4' title 'path', \
     $pm2 using 1:2 with points pt 9 ps 1.0 lc rgb '#d62728' title 'photon-map (sweep)', \
     $pmcurve2 using 1:2 with lines lw 2 lc rgb '#d62728' title 'photon-map (best)', \
     $front2 using 1:2 with points pt 6 ps 2.2 lw 1.5 lc rgb 'black' title 'Pareto frontier', \
     $presets2 using 1:2:3 with labels offset char 1.2,0.8 left font ',10' notitle
unset multiplot
