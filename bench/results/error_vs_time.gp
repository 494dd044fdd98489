$path0 << EOD
0.235767 3.58048 -
0.845144 0.843455 -
3.57954 0.210066 -
13.5615 0.055256 -
EOD
$pm0 << EOD
0.783146 0.0071007 preview
2.44503 0.00207456 final
1.82722 0.00371843 -
1.64588 0.00409273 -
4.5753 0.00155854 -
2.05722 0.00228147 -
3.05917 0.00192233 -
2.4436 0.00201619 -
2.02052 0.00223327 -
3.50799 0.00157651 -
6.04383 0.00127993 -
EOD
$pmcurve0 << EOD
0.783146 0.0071007 preview
1.64588 0.00409273 -
1.82722 0.00371843 -
2.02052 0.00223327 -
2.4436 0.00201619 -
3.05917 0.00192233 -
3.50799 0.00157651 -
4.5753 0.00155854 -
6.04383 0.00127993 -
EOD
$front0 << EOD
0.235767 3.58048 -
0.783146 0.0071007 preview
1.64588 0.00409273 -
1.82722 0.00371843 -
2.02052 0.00223327 -
2.4436 0.00201619 -
3.05917 0.00192233 -
3.50799 0.00157651 -
4.5753 0.00155854 -
6.04383 0.00127993 -
EOD
$presets0 << EOD
0.783146 0.0071007 preview
2.44503 0.00207456 final
EOD
$path1 << EOD
0.171288 0.226761 -
0.653728 0.0488014 -
2.64725 0.0107455 -
10.3624 0.00262325 -
EOD
$pm1 << EOD
0.446229 0.00596947 preview
1.17655 0.00153373 final
1.02509 0.0026902 -
1.0136 0.00190423 -
1.58269 0.00138981 -
0.869577 0.00187397 -
1.60373 0.00143214 -
1.38478 0.00147867 -
0.896453 0.00179461 -
1.50697 0.0010644 -
2.33508 0.00083496 -
EOD
$pmcurve1 << EOD
0.446229 0.00596947 preview
0.869577 0.00187397 -
0.896453 0.00179461 -
1.17655 0.00153373 final
1.38478 0.00147867 -
1.50697 0.0010644 -
2.33508 0.00083496 -
EOD
$front1 << EOD
0.171288 0.226761 -
0.446229 0.00596947 preview
0.869577 0.00187397 -
0.896453 0.00179461 -
1.17655 0.00153373 final
1.38478 0.00147867 -
1.50697 0.0010644 -
2.33508 0.00083496 -
EOD
$presets1 << EOD
0.446229 0.00596947 preview
1.17655 0.00153373 final
EOD
$path2 << EOD
0.0786871 7.44829 -
0.259735 2.70614 -
0.962791 0.842645 -
3.85084 0.111139 -
15.696 0.0386054 -
EOD
$pm2 << EOD
0.161789 0.0417172 preview
0.405611 0.0341776 final
0.350258 0.0339239 -
0.206448 0.0705821 -
1.0807 0.0447705 -
0.394464 0.0354265 -
0.397991 0.0315494 -
0.413116 0.0341776 -
0.440397 0.0341776 -
0.49802 0.0318795 -
0.704721 0.0323645 -
EOD
$pmcurve2 << EOD
0.161789 0.0417172 preview
0.350258 0.0339239 -
0.397991 0.0315494 -
EOD
$front2 << EOD
0.0786871 7.44829 -
0.161789 0.0417172 preview
0.350258 0.0339239 -
0.397991 0.0315494 -
EOD
$presets2 << EOD
0.161789 0.0417172 preview
0.405611 0.0341776 final
EOD
$path3 << EOD
0.319099 0.114523 -
1.13563 0.0260191 -
4.38947 0.00616203 -
16.9574 0.00151158 -
EOD
$pm3 << EOD
0.870319 0.0139629 preview
1.62342 0.0036056 final
1.34747 0.00533908 -
1.74404 0.00716777 -
2.26771 0.00191428 -
1.22672 0.00378104 -
2.44635 0.00347778 -
1.96503 0.00363279 -
1.28139 0.00368592 -
2.02654 0.00291094 -
3.10868 0.00260588 -
EOD
$pmcurve3 << EOD
0.870319 0.0139629 preview
1.22672 0.00378104 -
1.28139 0.00368592 -
1.62342 0.0036056 final
2.02654 0.00291094 -
2.26771 0.00191428 -
EOD
$front3 << EOD
0.319099 0.114523 -
0.870319 0.0139629 preview
1.22672 0.00378104 -
1.28139 0.00368592 -
1.62342 0.0036056 final
2.02654 0.00291094 -
2.26771 0.00191428 -
16.9574 0.00151158 -
EOD
$presets3 << EOD
0.870319 0.0139629 preview
1.62342 0.0036056 final
EOD
$path4 << EOD
0.30303 0.90606 -
1.10902 0.216089 -
4.37517 0.052179 -
18.1179 0.0131238 -
EOD
$pm4 << EOD
0.952071 0.00579784 preview
2.24536 0.00233236 final
2.06454 0.00291438 -
1.99367 0.00266964 -
3.07604 0.002136 -
1.60325 0.00289744 -
3.61629 0.00193386 -
2.71651 0.00222572 -
1.61009 0.00257833 -
2.69376 0.00211389 -
3.82894 0.00201185 -
EOD
$pmcurve4 << EOD
0.952071 0.00579784 preview
1.60325 0.00289744 -
1.61009 0.00257833 -
2.24536 0.00233236 final
2.69376 0.00211389 -
3.61629 0.00193386 -
EOD
$front4 << EOD
0.30303 0.90606 -
0.952071 0.00579784 preview
1.60325 0.00289744 -
1.61009 0.00257833 -
2.24536 0.00233236 final
2.69376 0.00211389 -
3.61629 0.00193386 -
EOD
$presets4 << EOD
0.952071 0.00579784 preview
2.24536 0.00233236 final
EOD
$path5 << EOD
0.825401 0.249629 -
3.27989 0.0462991 -
12.6636 0.0189438 -
54.0003 0.00506844 -
EOD
$pm5 << EOD
2.49727 0.00299958 preview
9.19556 0.00181443 final
6.32187 0.00193366 -
9.50122 0.00190706 -
9.4138 0.00170313 -
7.44627 0.00233119 -
12.5558 0.00147078 -
10.5236 0.00157614 -
8.46748 0.00191493 -
14.7892 0.00176282 -
25.6908 0.0017397 -
EOD
$pmcurve5 << EOD
2.49727 0.00299958 preview
6.32187 0.00193366 -
8.46748 0.00191493 -
9.19556 0.00181443 final
9.4138 0.00170313 -
10.5236 0.00157614 -
12.5558 0.00147078 -
EOD
$front5 << EOD
0.825401 0.249629 -
2.49727 0.00299958 preview
6.32187 0.00193366 -
8.46748 0.00191493 -
9.19556 0.00181443 final
9.4138 0.00170313 -
10.5236 0.00157614 -
12.5558 0.00147078 -
EOD
$presets5 << EOD
2.49727 0.00299958 preview
9.19556 0.00181443 final
EOD
$path6 << EOD
0.360243 0.449979 -
1.16858 0.120524 -
4.34706 0.0302586 -
16.19 0.00737265 -
EOD
$pm6 << EOD
0.985192 0.0304947 preview
3.00676 0.00721378 final
2.40267 0.0123259 -
2.31798 0.00823548 -
5.36517 0.00679878 -
2.8958 0.00730463 -
4.06715 0.0071793 -
3.39865 0.00720595 -
2.64517 0.00724493 -
4.5032 0.00423572 -
7.62361 0.00253771 -
EOD
$pmcurve6 << EOD
0.985192 0.0304947 preview
2.31798 0.00823548 -
2.64517 0.00724493 -
3.00676 0.00721378 final
3.39865 0.00720595 -
4.06715 0.0071793 -
4.5032 0.00423572 -
7.62361 0.00253771 -
EOD
$front6 << EOD
0.360243 0.449979 -
0.985192 0.0304947 preview
2.31798 0.00823548 -
2.64517 0.00724493 -
3.00676 0.00721378 final
3.39865 0.00720595 -
4.06715 0.0071793 -
4.5032 0.00423572 -
7.62361 0.00253771 -
EOD
$presets6 << EOD
0.985192 0.0304947 preview
3.00676 0.00721378 final
EOD
$path7 << EOD
0.924767 3.67449 -
3.53177 0.911427 -
14.1338 0.224384 -
EOD
$pm7 << EOD
2.32681 0.00788418 preview
6.53626 0.00338816 final
4.41928 0.00427286 -
4.48657 0.00573153 -
12.2483 0.00279485 -
6.41599 0.00373847 -
8.23691 0.00324613 -
7.45317 0.00333848 -
6.58444 0.0033665 -
11.1002 0.00308016 -
21.5957 0.00292267 -
EOD
$pmcurve7 << EOD
2.32681 0.00788418 preview
4.41928 0.00427286 -
6.41599 0.00373847 -
6.53626 0.00338816 final
6.58444 0.0033665 -
7.45317 0.00333848 -
8.23691 0.00324613 -
11.1002 0.00308016 -
12.2483 0.00279485 -
EOD
$front7 << EOD
0.924767 3.67449 -
2.32681 0.00788418 preview
4.41928 0.00427286 -
6.41599 0.00373847 -
6.53626 0.00338816 final
6.58444 0.0033665 -
7.45317 0.00333848 -
8.23691 0.00324613 -
11.1002 0.00308016 -
12.2483 0.00279485 -
EOD
$presets7 << EOD
2.32681 0.00788418 preview
6.53626 0.00338816 final
EOD
$path8 << EOD
0.687268 0.220313 -
2.66108 0.0486853 -
10.5496 0.0106704 -
EOD
$pm8 << EOD
1.50117 0.00597587 preview
3.0047 0.00141719 final
2.31925 0.00241339 -
2.91547 0.00183713 -
3.57671 0.00124524 -
2.63902 0.00176676 -
4.62486 0.00129747 -
3.83899 0.00139104 -
3.15006 0.00139551 -
4.89579 0.000937445 -
7.32603 0.000730663 -
EOD
$pmcurve8 << EOD
1.50117 0.00597587 preview
2.31925 0.00241339 -
2.63902 0.00176676 -
3.0047 0.00141719 final
3.15006 0.00139551 -
3.57671 0.00124524 -
4.89579 0.000937445 -
7.32603 0.000730663 -
EOD
$front8 << EOD
0.687268 0.220313 -
1.50117 0.00597587 preview
2.31925 0.00241339 -
2.63902 0.00176676 -
3.0047 0.00141719 final
3.15006 0.00139551 -
3.57671 0.00124524 -
4.89579 0.000937445 -
7.32603 0.000730663 -
EOD
$presets8 << EOD
1.50117 0.00597587 preview
3.0047 0.00141719 final
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
set xrange [0.157178:20.3423]
set yrange [0.000639965:14.3219]
plot $path0 using 1:2 with linespoints lw 2 pt 7 ps 0.8 lc rgb '#1f77b4' title 'path', \
     $pm0 using 1:2 with points pt 9 ps 1.0 lc rgb '#d62728' title 'photon-map (sweep)', \
     $pmcurve0 using 1:2 with lines lw 2 lc rgb '#d62728' title 'photon-map (best)', \
     $front0 using 1:2 with points pt 6 ps 2.2 lw 1.5 lc rgb 'black' title 'Pareto frontier', \
     $presets0 using 1:2:3 with labels offset char 1.2,0.8 left font ',10' notitle
set title 'cornell-box-diffuse'
set xrange [0.114192:15.5436]
set yrange [0.00041748:0.907045]
plot $path1 using 1:2 with linespoints lw 2 pt 7 ps 0.8 lc rgb '#1f77b4' title 'path', \
     $pm1 using 1:2 with points pt 9 ps 1.0 lc rgb '#d62728' title 'photon-map (sweep)', \
     $pmcurve1 using 1:2 with lines lw 2 lc rgb '#d62728' title 'photon-map (best)', \
     $front1 using 1:2 with points pt 6 ps 2.2 lw 1.5 lc rgb 'black' title 'Pareto frontier', \
     $presets1 using 1:2:3 with labels offset char 1.2,0.8 left font ',10' notitle
set title 'caustic-area'
set xrange [0.0524581:23.5439]
set yrange [0.0157747:29.7932]
plot $path2 using 1:2 with linespoints lw 2 pt 7 ps 0.8 lc rgb '#1f77b4' title 'path', \
     $pm2 using 1:2 with points pt 9 ps 1.0 lc rgb '#d62728' title 'photon-map (sweep)', \
     $pmcurve2 using 1:2 with lines lw 2 lc rgb '#d62728' title 'photon-map (best)', \
     $front2 using 1:2 with points pt 6 ps 2.2 lw 1.5 lc rgb 'black' title 'Pareto frontier', \
     $presets2 using 1:2:3 with labels offset char 1.2,0.8 left font ',10' notitle
set title 'spheres-room'
set xrange [0.212732:25.4361]
set yrange [0.000755791:0.45809]
plot $path3 using 1:2 with linespoints lw 2 pt 7 ps 0.8 lc rgb '#1f77b4' title 'path', \
     $pm3 using 1:2 with points pt 9 ps 1.0 lc rgb '#d62728' title 'photon-map (sweep)', \
     $pmcurve3 using 1:2 with lines lw 2 lc rgb '#d62728' title 'photon-map (best)', \
     $front3 using 1:2 with points pt 6 ps 2.2 lw 1.5 lc rgb 'black' title 'Pareto frontier', \
     $presets3 using 1:2:3 with labels offset char 1.2,0.8 left font ',10' notitle
set title 'sunlit-room'
set xrange [0.20202:27.1768]
set yrange [0.00096693:3.62424]
plot $path4 using 1:2 with linespoints lw 2 pt 7 ps 0.8 lc rgb '#1f77b4' title 'path', \
     $pm4 using 1:2 with points pt 9 ps 1.0 lc rgb '#d62728' title 'photon-map (sweep)', \
     $pmcurve4 using 1:2 with lines lw 2 lc rgb '#d62728' title 'photon-map (best)', \
     $front4 using 1:2 with points pt 6 ps 2.2 lw 1.5 lc rgb 'black' title 'Pareto frontier', \
     $presets4 using 1:2:3 with labels offset char 1.2,0.8 left font ',10' notitle
set title 'foggy-room'
set xrange [0.550267:81.0005]
set yrange [0.00073539:0.998514]
plot $path5 using 1:2 with linespoints lw 2 pt 7 ps 0.8 lc rgb '#1f77b4' title 'path', \
     $pm5 using 1:2 with points pt 9 ps 1.0 lc rgb '#d62728' title 'photon-map (sweep)', \
     $pmcurve5 using 1:2 with lines lw 2 lc rgb '#d62728' title 'photon-map (best)', \
     $front5 using 1:2 with points pt 6 ps 2.2 lw 1.5 lc rgb 'black' title 'Pareto frontier', \
     $presets5 using 1:2:3 with labels offset char 1.2,0.8 left font ',10' notitle
set title 'glossy-objects'
set xrange [0.240162:24.285]
set yrange [0.00126886:1.79992]
plot $path6 using 1:2 with linespoints lw 2 pt 7 ps 0.8 lc rgb '#1f77b4' title 'path', \
     $pm6 using 1:2 with points pt 9 ps 1.0 lc rgb '#d62728' title 'photon-map (sweep)', \
     $pmcurve6 using 1:2 with lines lw 2 lc rgb '#d62728' title 'photon-map (best)', \
     $front6 using 1:2 with points pt 6 ps 2.2 lw 1.5 lc rgb 'black' title 'Pareto frontier', \
     $presets6 using 1:2:3 with labels offset char 1.2,0.8 left font ',10' notitle
set title 'cornell-box-512'
set xrange [0.616511:32.3936]
set yrange [0.00139742:14.698]
plot $path7 using 1:2 with linespoints lw 2 pt 7 ps 0.8 lc rgb '#1f77b4' title 'path', \
     $pm7 using 1:2 with points pt 9 ps 1.0 lc rgb '#d62728' title 'photon-map (sweep)', \
     $pmcurve7 using 1:2 with lines lw 2 lc rgb '#d62728' title 'photon-map (best)', \
     $front7 using 1:2 with points pt 6 ps 2.2 lw 1.5 lc rgb 'black' title 'Pareto frontier', \
     $presets7 using 1:2:3 with labels offset char 1.2,0.8 left font ',10' notitle
set title 'cornell-box-diffuse-512'
set xrange [0.458179:15.8244]
set yrange [0.000365332:0.881251]
plot $path8 using 1:2 with linespoints lw 2 pt 7 ps 0.8 lc rgb '#1f77b4' title 'path', \
     $pm8 using 1:2 with points pt 9 ps 1.0 lc rgb '#d62728' title 'photon-map (sweep)', \
     $pmcurve8 using 1:2 with lines lw 2 lc rgb '#d62728' title 'photon-map (best)', \
     $front8 using 1:2 with points pt 6 ps 2.2 lw 1.5 lc rgb 'black' title 'Pareto frontier', \
     $presets8 using 1:2:3 with labels offset char 1.2,0.8 left font ',10' notitle
unset multiplot
